// One client's editing tool in a session (issue 11 §1, docs/collaboration.md): its regions and
// deformation fields, its collision detector and settings, what it found colliding, its step counter
// and merge memo. The model, the version, the row versions and the history belong to the session;
// a session holds one Tool per author (client id; "" in-process is the default tool).
//
// Lock: the rows a tool can move are its deformable rows (every row outside its zero region, i.e.
// every surfel with s > 0); they are disjoint from every other tool's (EditSession::set_regions).
// Everything else is rigid to the tool. When another tool's op changes rows the tool treats as rigid
// (moves, inserts or removes them), the tool is `stale` and its detector catches up before the tool's
// next step (EditSession::sync_tool): while every change since is a move of known rows (`stale_rows`),
// the detector updates its structures for those rows only (CollisionDetector::on_rigid_moved);
// otherwise (rows inserted or removed, an undo that brought back an older detector, a detector that
// cannot follow) it is re-initialised from the model as it is then.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

// What a tool keeps for merges: its deformable surfels when its detector was last reset (the
// "original" surfaces of merge_regions), and the crease points of its last merge (intersection_curves).
// The origins are the detector's own copy when it keeps one from that very reset (Robust's original model,
// CollisionDetector::reset_rows): `origins_in_detector`, and the two arrays here are empty. Before the tool's
// detector is replaced by one reset at another time (a stale tool re-initialised, a step rolled back without
// its detector states), Tool::own_origins copies them here.
struct MergeMemo {
  Points origin_positions;  // #D by 3: deformable surfels at the last reset (set_regions, configure, merge)
  Points origin_normals;    // #D by 3, unit
  bool origins_in_detector = false;  // the origins are the tool's detector's reset_rows() (both arrays empty)
  Points crease_positions;  // #K by 3: surfels the last merge's crease moved, on the intersection
  Values crease_radii;      // #K: their radii
  // The blend tool's inputs (session_blend.cpp): what blend() starts from and what it restores.
  IdList features;          // feature surfel ids of the last merge or boolean (blend's default), ascending
  IdList crease_moved;      // ids the last crease moved and clipped (not yet restored by a blend)
  Points crease_from;       // #crease_moved by 3: their positions before the crease
  IdList crease_copies;     // ids of the last crease's gap-covering copies (not yet removed by a blend)
  bool open_region = false; // the features come from a boolean (open blend region, §12.4.1)
};

// A tool's state as a history image holds it (history.hpp: WholeImage keeps every tool's).
struct ToolImage {
  std::optional<DeformationFields> fields;      // none before set_regions / after a release / fields_kept
  bool fields_kept = false;                     // the op kept the fields (configure): restoring keeps the
                                                // tool's own, which are the same (no copy held)
  SessionSettings settings;                     // its settings (history_mb is the session's, see below)
  std::shared_ptr<CollisionDetector> detector;  // the detector object (may be null)
  bool derive_detector = false;                 // detector not held: restoring re-derives it (a reset from
                                                // the model then, which is the model it was reset from)
  MergeMemo merge;
  IdList colliding;
  std::uint64_t steps = 0;
  bool stale = false;

  std::size_t bytes() const;
};

struct Tool {
  // Per tool: regions, fields, detector and every setting but `history` (history_mb: the undo
  // history is the session's; EditSession keeps it and settings() reports it in every tool's).
  std::unique_ptr<DeformationFields> fields;    // built by set_regions; null: no regions, no lock
  SessionSettings settings;                     // collision, hierarchy, simplification, resampling, response, blend
  std::shared_ptr<CollisionDetector> detector;  // built when regions are set and algorithm != none
  IdList colliding;                             // colliding ids after its last step, ascending
  std::uint64_t steps = 0;                      // its steps so far (StepResult::seq)
  MergeMemo merge;                              // origins and last crease (session_merge.cpp)
  bool stale = false;  // rows it treats as rigid changed under its detector since the detector was built
  bool stale_rows_known = false;  // when stale: every change since moved rows of `stale_rows`, nothing else
  IndexList stale_rows;           // when stale_rows_known: the rows moved since, ascending (model rows)
  // What rows it treats as rigid were before other tools' ops moved them, as its detector last saw them
  // (first move wins): `held_rows` ascending (while stale, a superset of stale_rows), `held` one entry each.
  IndexList held_rows;
  RigidRows held;
  // Scratch, not part of the state (never in an image):
  bool journaling = false;  // during deform(): the detector's journal holds the step's before-states
  Points previous;          // #P by 3: positions before the current step (reused between steps)
  // Nonzero: at this session version `previous` has the model's rows and equals the positions outside
  // fields->deformable (set by a completed step; any other change makes a new version).
  std::uint64_t previous_at = 0;
  std::shared_ptr<const IndexList> shared_rows;  // the row list of its last rows image (shared by images)
  std::shared_ptr<const IndexList> shared_bent;  // the `bent` list of its last step's rows image (likewise)
  std::shared_ptr<const IdList> shared_touched;  // the ids its last step touched (shared by history entries)
  // The detector is exactly as a reset from the model made it, and nothing changed since: while the
  // session's version is `fresh_at` (a nonzero version at which it was reset) and the detector object
  // is `fresh_object` (and the tool is not stale). A tool image then need not hold the detector.
  std::uint64_t fresh_at = 0;
  const CollisionDetector* fresh_object = nullptr;

  bool has_regions() const { return fields != nullptr; }
  // Copies the state (the detector object itself, or an independent clone when `clone`: nullptr
  // when the detector cannot be cloned).
  ToolImage image(bool clone) const;
  // Puts an image back (`clone`: the image's detector is cloned, so the image can be reused). With
  // derive_detector, the detector is null after it: the caller re-derives it (EditSession::restore).
  // With fields_kept, the fields stay as they are.
  void restore(const ToolImage& image, bool clone);
  // Whether the detector is fresh at session version `version` (see fresh_at).
  bool detector_fresh(std::uint64_t version) const {
    return detector && !stale && fresh_at != 0 && fresh_at == version && fresh_object == detector.get();
  }
  void mark_fresh(std::uint64_t version) {
    fresh_at = version;
    fresh_object = detector.get();
  }
  // The merge origins (MergeMemo): the memo's arrays, or the detector's reset rows (origins_in_detector).
  CollisionDetector::ResetRows merge_origins() const;
  // Before the detector is replaced by one not reset now from the same model: the origins move into the memo.
  void own_origins();
  // Frees the regions, the detector and what they found (the settings stay).
  void clear_regions();
  // Another tool's op changed rows this tool treats as rigid: `moved` (ascending model rows, the row
  // count unchanged) when it only moved those, nullptr when anything may have changed.
  void mark_stale(const IndexList* moved);
  // The detector caught up with the model (reset or updated): not stale.
  void clear_stale();
  // Before another tool's op moves `rows` (ascending) of `model`: keeps what they are now (held), for the
  // rows not kept yet since the detector last caught up; nothing when the tool has no detector or is stale
  // with unknown rows.
  void hold_rigid(const SurfelModel& model, const IndexList& rows);
  // What stale_rows were (one entry each, from `held`); false when one of them is not held.
  bool held_before(RigidRows& out) const;
};

// Appends one row per parent (a row of `f`) inheriting its region and fields (the model got them appended).
void extend_fields(DeformationFields& f, const IndexList& parents);
// Keeps the rows with keep[r] (one flag per row of `f`), in order.
void compact_fields(DeformationFields& f, const std::vector<bool>& keep);

// How many rows are deformable (not Zero) in both `a` and `b` (#P each).
std::size_t lock_overlap(const std::vector<Region>& a, const std::vector<Region>& b);

}  // namespace surfeledit
