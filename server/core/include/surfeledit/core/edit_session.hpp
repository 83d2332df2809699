// An editing session: one surfel model, a version counter, the edit history, and one editing tool
// per author (tool.hpp: regions, deformation fields, collision detector and settings). Every call
// that acts on a tool takes its author (a client id; "" in-process, the default tool): a single
// author works exactly as a session with one set of regions (docs/collaboration.md).
//
// Every mutating call validates everything first and throws before changing anything,
// so a failed request leaves the session exactly as it was. Not thread-safe: the owner
// serialises calls.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/boolean.hpp"
#include "surfeledit/core/history.hpp"
#include "surfeledit/core/row_versions.hpp"
#include "surfeledit/core/holes.hpp"
#include "surfeledit/core/response/curves.hpp"
#include "surfeledit/core/selector.hpp"
#include "surfeledit/core/session_snapshot_view.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "surfeledit/core/surfel_model.hpp"
#include "surfeledit/core/tool.hpp"

namespace surfeledit {

// SessionParams::threads' bound: tests oversubscribe a few cores; 2^31 made libgomp abort (docs/hardening.md).
constexpr int kMaxSessionThreads = 256;

struct SessionParams {
  int threads = 0;  // worker threads for batch work, and the `threads` setting a new tool starts with (at most
                    // the hardware threads); 0 = all hardware threads; at most kMaxSessionThreads
  bool incremental_rigid = true;  // a stale tool's detector follows moved rigid rows (on_rigid_moved);
                                  // false: it is always re-initialised (the reference, for tests and bench)
};

// What changed since a given version.
struct Changes {
  bool full = false;  // the model was replaced since then, or `since` is below the row versions' floor (a
                      // session past 2^32 versions, row_versions.hpp): `changed` lists every surfel
  IdList changed;     // ids whose attributes changed (or that were inserted), ascending
  IndexList rows;     // instead of `changed` when asked for (changes_since(since, true)): their rows,
                      // ascending (none when `full`)
  IdList removed;     // ids removed since then
};

// One acceleration structure or field a session holds, and its memory.
struct StructureInfo {
  std::string name;
  std::size_t bytes = 0;
};

struct SessionReport {
  Index surfels = 0;
  std::vector<StructureInfo> structures;  // model arrays first, then what was built
  std::size_t total_bytes = 0;
  double bytes_per_surfel = 0.0;
  std::string hierarchy_status;  // "fresh" | "refit" | "rebuilding", "" without a hierarchy
  // The "history" structure split by image kind (history.hpp): "rows" (steps), "tool" (set_regions,
  // configure, release), "whole" (every other op); each kind listed once, with its entry count.
  struct HistoryKind {
    std::string kind;
    std::size_t entries = 0;
    std::size_t bytes = 0;
  };
  std::vector<HistoryKind> history_kinds;  // rows, tool, whole (entries by image kind), detectors (objects
                                           // only the history keeps alive: entries = objects)
};

// What a back-off response did (§7 c).
struct BackoffInfo {
  int iterations = 0;         // re-tests made
  double kept = 1.0;          // fraction of the requested step that was kept, in [0, 1]
  double final_depth = 0.0;   // largest penetration depth after the response, model units
};

// What one deformation step did.
struct StepResult {
  std::uint64_t seq = 0;       // 1-based step number in this session
  IndexList moved;             // rows whose attributes changed (moved or split), ascending
  IdList inserted;             // ids of surfels inserted by resampling (appended rows)
  Vec3 center = Vec3::Zero();  // rotation centre used
  bool detected = false;       // a collision detector ran
  IdList colliding;            // colliding surfel ids after the step and its response, ascending (response
                               // "cancelled": those that would have collided; the session keeps its own)
  std::vector<double> depths;  // per colliding id: penetration depth estimate, model units
  CollisionStats stats;        // of the detector (zeros when none ran)
  double deform_ms = 0.0;      // time of the deformation itself
  double resample_ms = 0.0;    // time of resampling
  std::string response = "none";  // "none" (nothing collided or no detector), "reported", "cancelled",
                                  // "backed_off", "merged"; `colliding` is the state after the response
                                  // (cancelled, merged: the ids that collided; merged removed them)
  BackoffInfo backoff;            // response "backed_off" only
  IdList features;                // response "merged": feature surfel ids (both sides), ascending
  double response_ms = 0.0;       // time of the response (cancel / back-off / merge)
  double history_ms = 0.0;        // time of recording the step's before-image in the history
};

// What EditSession::merge did (§7 d).
struct MergeOutcome {
  IdList removed;            // ids removed (colliding deformable surfels, zero surfels inside), ascending
  IdList features;           // feature surfel ids of both sides (kept), ascending
  IdList moved;              // ids the crease moved onto the intersection (clipped), ascending
  IdList inserted;           // ids of the crease's gap-covering copies
  std::vector<Curve> curves; // intersection curves through the moved surfels (default CurveParams)
  double merge_ms = 0.0;     // time of merge_regions
  double crease_ms = 0.0;    // time of the crease (computing and applying it)
  double curves_ms = 0.0;    // time of the intersection curves
  double total_ms = 0.0;     // the whole merge, model changes and detector reset included
};

// What EditSession::blend did (thesis §12.3).
struct BlendOutcome {
  Index particles = 0;         // particles the blend started with (the blend region, crease copies excluded)
  IdList moved;                // ids of blend region surfels that became particles again (same ids), ascending
  IdList inserted;             // ids of surfels made from particles split off (adaptive)
  IdList removed;              // ids removed: particles killed (adaptive) and the crease's gap-covering copies
  std::vector<double> energy;  // per iteration: the particle system's energy before it (spacing units)
  int substeps = 0;            // sub-steps over all iterations (dt above the stable step is split)
  double ms = 0.0;             // the whole blend
};

// One hole fill_holes() filled.
struct HoleOutcome {
  IdList boundary;        // ids of its boundary surfels, ascending
  double diameter = 0.0;  // largest distance between two of them, model units
  IdList inserted;        // ids of the surfels that fill it
};

// What EditSession::fill_holes did (thesis §12.4.2).
struct FillOutcome {
  std::vector<HoleOutcome> holes;  // the holes filled (loops no wider than max_diameter)
  Index skipped = 0;               // loops wider than max_diameter (open borders), left alone
  IdList inserted;                 // every inserted id, ascending
  double ms = 0.0;
};

// Region selection: explicit ids and/or selectors, merged.
struct RegionSpec {
  IdList ids;
  std::vector<Selector> selectors;
};

class EditSession {
 public:
  explicit EditSession(std::string name, SessionParams params = {});
  ~EditSession();

  const std::string& name() const { return name_; }
  std::uint64_t version() const { return version_; }
  bool has_model() const { return !model_.empty(); }
  // Throws Conflict ("no model loaded") when empty.
  const SurfelModel& model() const;
  // The tool of `tool` (an author; "" the default tool): regions and fields (nullptr without).
  bool has_regions(const std::string& tool = "") const { return fields(tool) != nullptr; }
  const DeformationFields* fields(const std::string& tool = "") const;
  // Authors that have a tool, ascending, and how many rows each one's lock holds (its deformable rows).
  std::vector<std::pair<std::string, Index>> tools() const;

  // Replaces the model; every tool's regions are cleared. Bumps the version.
  // Every mutating call takes the author of the change (a client id; "" in-process) for history().
  void load(SurfelModel model, const std::string& author = "");
  // Resolves both specs, checks they are non-empty and disjoint, computes the deformation
  // fields of the author's tool. Surfels in neither region blend between them. Lock: Conflict (field
  // "regions", naming the other author and how many surfels overlap) when the new deformable rows
  // (every row outside `zero`) meet another tool's; nothing changes then. Bumps the version.
  void set_regions(const RegionSpec& zero, const RegionSpec& one, const std::string& author = "");
  // Ids matching a spec (ids validated, selectors applied to current positions), ascending.
  IdList resolve(const RegionSpec& spec, const std::string& field) const;
  // Applies one step, then resampling and collision detection as configured; requires regions.
  // Bumps the version (not when the response cancelled the step). The response (settings "response")
  // runs after detection.
  StepResult deform(const DeformParams& params, const std::string& author = "");

  // Session settings (collision algorithm, heuristics, resampling); validated before anything
  // changes. Re-initialises the detector from the current model when regions are set (its
  // "original" model is the current one); the model and the version do not change.
  // Settings act on the author's tool, but for history_mb, which is the session's.
  void configure(const std::vector<NamedSetting>& changes, const std::string& author = "");
  SessionSettings settings(const std::string& tool = "") const;
  // Frees the author's tool: its regions, detector and lock (its settings stay). One history entry
  // ("release", no surfel touched; undo takes the regions and the lock back) and a new version;
  // false and no change when the tool has no regions.
  bool release(const std::string& author = "");
  // Starts a background rebuild of the deformable tree from the model as it is now (rebuild on
  // idle, e.g. when a drag ends); the next step that finds it finished swaps it in. Never waits.
  // False when there is no deformable tree or a rebuild is under way.
  bool rebuild_hierarchies(const std::string& tool = "");
  // Status and build times of the detector's trees (empty without a hierarchy).
  HierarchyInfo hierarchy_info(const std::string& tool = "") const;
  // Colliding ids after the tool's last step (empty before any step / after a reset), ascending.
  const IdList& colliding(const std::string& tool = "") const;
  // Removes surfels (validated first: unknown ids, leaving a tool's zero or one region empty, or
  // surfels another tool's lock holds (Conflict, field "ids"), throw and change nothing); the author's
  // detector keeps the state of the others. Bumps the version.
  void remove(const IdList& ids, const std::string& author = "");

  // Merge (union) of the deformed region with the zero region (§7 d): removes the colliding deformable
  // surfels and the zero surfels inside the deformed region; `crease`: moves the feature surfels onto
  // the intersection, clips them and covers gaps (response/crease.hpp). The detector re-initialises from
  // the merged model. One history entry ("merge"). Conflict without regions, or when the removal would
  // leave the zero or one region empty; nothing colliding: an empty outcome, nothing changes. Bumps
  // the version when it changed something.
  MergeOutcome merge(bool crease = true, const std::string& author = "");
  // Blend tool (session_blend.cpp, thesis §12.3): the blend region around `features` (ids; none: the feature
  // surfels of the last merge or boolean, Conflict before one) becomes particles (the crease there undone:
  // moved surfels back, clips cleared, copies removed), runs `params.iterations` iterations and becomes
  // surfels again (same ids; split-off particles inserted, killed ones removed). Calling it again continues.
  // The settings blend_* override params.neighbour_factor and gamma, and choose the repulsion after a boolean.
  // One history entry ("blend"); validates first (InvalidArgument / NotFound naming the field).
  BlendOutcome blend(const BlendParams& params, const std::optional<IdList>& features = std::nullopt,
                     const std::string& author = "");
  // Boolean operation of the model (A) with `b` (thesis §12.4.1, boolean.hpp): A's dropped surfels are removed
  // (ids kept for the rest), B's kept surfels inserted (normals flipped for difference), the feature surfels
  // kept for blend(). The regions are cleared (the model's shape changed as by a load). One history entry
  // ("boolean"); Conflict when nothing would be left. `removed` A's dropped ids, `inserted` B's new ids.
  MergeOutcome boolean(BooleanOp op, SurfelArrays b, const BooleanParams& params = {},
                       const std::string& author = "");
  // Hole filling (thesis §12.4.2, holes.hpp): loops of boundary surfels (detected, or `boundary` ids) no
  // wider than params.max_diameter are filled. One history entry ("fill_holes") when it inserted surfels.
  FillOutcome fill_holes(const HoleParams& params, const std::optional<IdList>& boundary = std::nullopt,
                         const std::string& author = "");

  // Curves through the surfels the last merge moved onto the intersection; Conflict before any merge
  // with a crease. Validates `params` (InvalidArgument naming the field).
  std::vector<Curve> intersection_curves(const CurveParams& params = {}, const std::string& tool = "") const;

  // Undo / redo the session's last applied / last undone change, whoever made it (history.hpp): undo(author)
  // of that change's author. With one author (or in the session's strict order) the state then equals the
  // one before / after it bit for bit. Each bumps the version (the restored rows count as changed since)
  // and returns it. Conflict when there is nothing to undo / redo. Every detector (hierarchies and
  // approximate detection included) is restored exactly: later steps give the results a session that never
  // took the undone op gives.
  std::uint64_t undo();
  std::uint64_t redo();
  // Per author (issue 11 §3): undoes the author's own last applied change / redoes its last undone one.
  // While no other author's entry was applied, undone or redone after it, exactly undo() / redo().
  // Otherwise only the entry's own part comes back -- its surfels bit for bit and its author's tool (whose
  // detector is then re-initialised at its next step) -- and it is refused (Conflict, field "history",
  // naming the other op's version and author) when such a later entry touched any surfel the entry
  // touched, or inserted or removed surfels (rows renumbered), or when the entry itself inserted or removed
  // surfels (those can only come back whole), or when its regions would overlap another tool's lock.
  // Refused: nothing changes.
  std::uint64_t undo(const std::string& author);
  std::uint64_t redo(const std::string& author);
  // The entries, oldest first (in the order first applied; undone ones flagged).
  std::vector<HistoryItem> history() const { return history_.items(); }

  // Changes since version `since` (since >= version() gives none).
  // `rows`: the changed surfels as rows (Changes::rows), not ids -- what an update copies, without an
  // id-to-row lookup per surfel (at 1M surfels a drag step's update was 4.7 ms of it, RESULTS §46).
  Changes changes_since(std::uint64_t since, bool rows = false) const;
  SessionReport report() const;
  std::uint64_t state_hash() const;

  // Snapshots (session_snapshot.cpp, docs/journal.md): the whole session in a versioned binary format --
  // model, row versions, removal log, rest radii, version, every tool, and the history (entries, images,
  // spare buffers) with every detector object written once (shared objects stay shared) through its own
  // save_state(), never rebuilt: a restored session's every later step, undo and redo give what this one's
  // give. not_snapshottable(): why not ("" when it can be): a detector, live or in the history, whose type
  // has no snapshot (detector_snapshot.hpp). save(): Internal when not snapshottable. restore(): replaces
  // everything by a saved state (the name and SessionParams stay this session's); InvalidArgument
  // ("snapshot") for a corrupt or unknown-version snapshot, and then nothing changed.
  // snapshot_view(): the same snapshot taken now and encoded later, on any thread, while this session goes
  // on (session_snapshot_view.hpp): it encodes what is small or changes in place now (a copy of about the
  // model's size) and shares the history's images; save(out) is snapshot_view().encode(out). Internal
  // when not snapshottable.
  std::string not_snapshottable() const;
  SessionSnapshotView snapshot_view() const;
  void save(SnapshotWriter& out) const;
  void restore(SnapshotReader& in);

 private:
  void touch_rows(const IndexList& rows);
  // Tools (tool.hpp). use(): the author's tool becomes the acting one (tool_), created with new_settings()
  // when it has none. find_tool(): nullptr when none.
  Tool& use(const std::string& author);
  const Tool* find_tool(const std::string& author) const;
  // The author's tool's settings (new_settings() when it has none), with the session's history bound.
  SessionSettings settings_of(const std::string& author) const;
  // A new tool's settings: the defaults, with the session's history bound, and its threads (at most the
  // hardware threads, the setting's range) as the detection threads.
  SessionSettings new_settings() const;
  // Every tool but the acting one treats rows the acting op changed as rigid: stale (Tool::mark_stale;
  // `moved`: the op only moved those rows, nullptr: anything may have changed). sync_tool(): when the
  // acting tool is stale, its detector follows the moved rows (on_rigid_moved, on a clone when a history
  // image still refers to the detector object) or, when that cannot be, is re-initialised.
  void mark_others_stale(const IndexList* moved = nullptr);
  // Before an op moves `rows` (ascending): every other tool keeps what they are now (Tool::hold_rigid), for
  // its detector's on_rigid_moved at that tool's next step.
  void hold_for_others(const IndexList& rows);
  void sync_tool();
  // The model's arrays with `f`'s regions, as a detector sees them.
  CollisionScene scene_of(const DeformationFields& f) const {
    return CollisionScene{model_.positions(), model_.normals(), model_.radii(), f.regions};
  }
  // Conflict (naming `field` and the other author) when a row with keep[r] false, or a row of
  // `parents` (rows that will get children), is in another tool's lock.
  void check_unlocked(const std::vector<bool>* keep, const IndexList* parents, const char* field) const;
  // History (session_history.cpp). An image of the rows a step may move (the deformable rows), or of
  // everything (`clone`: the detector is cloned, else the live object is shared).
  // `subset`: the detector saves only `rows` too (else every deformable row).
  // `detector` false: no detector states (the step's journal holds them, see journaling_).
  // `bent`: the rows whose normals and tangents are kept (null: all; RowsImage::bent).
  // `previous` (#P by 3, or null): the same pass copies the rows' positions into it too (a step's
  // `previous`, step_once).
  SessionImage capture_rows(const IndexList& rows, bool subset = false, bool detector = true,
                            std::shared_ptr<const IndexList> bent = nullptr, Points* previous = nullptr);
  // The rows among the acting tool's deformable rows whose normals or tangents a step of `params` may
  // change; null when that may be all of them (a rotation, or no F1 row).
  std::shared_ptr<const IndexList> step_bent_rows(const DeformParams& params);
  // A step took `before` (a rows image) and has not changed rows, fields or settings otherwise: the whole
  // session as it was before the step, but for the detector, which is the live object (its state is the
  // caller's to put back); for a merge after the step (response "merge").
  SessionImage whole_before_step(const SessionImage& before) const;
  // The detector states of a step's rows image: the journal's while it runs, else the image's own.
  std::shared_ptr<const DetectorImage> step_detector_image(const SessionImage& before) const;
  // `clone`: the op changes the acting tool's detector in place, so the image keeps the live object (which
  // the rows images of earlier entries refer to) and the tool goes on with an independent clone.
  SessionImage capture_whole(bool clone);
  // The acting tool alone (an op that changes nothing else: set_regions, configure, release); `keep_fields`:
  // the op keeps the tool's fields (configure), so the image holds none.
  SessionImage capture_tool(bool keep_fields);
  // Puts a tool image back into `t`, re-deriving a detector the image does not hold (derive_detector)
  // from the model as it is now.
  void restore_tool(Tool& t, const ToolImage& image, bool clone);
  // Puts an image back (`clone`: a Whole image's detector is cloned, so the image can be reused).
  void restore(const SessionImage& image, bool clone);
  // Appends rows (the last parents.size() rows) as extend_rows does, with or without regions.
  void extend_any(const IndexList& parents);
  // Appends the entry of an op that just bumped the version; `before` is the image before it. `moved`:
  // the rows the op moved when it did nothing else to rows (a step), for the other tools (mark_others_stale).
  void record(const char* op, const std::string& author, IdList touched, SessionImage before,
              const IndexList* moved = nullptr);
  // The same with the touched ids already ascending, unique and shared (step_touched).
  void record_shared(const char* op, const std::string& author, std::shared_ptr<const IdList> touched,
                     SessionImage before, const IndexList* moved = nullptr);
  // The ids of a step's moved rows, ascending: the acting tool's last list (Tool::shared_touched) when they are
  // the same, as step after step of a drag they are (at 1M surfels ~2 MB an entry not allocated again).
  std::shared_ptr<const IdList> step_touched(const IndexList& moved);
  std::uint64_t swap_entry(HistoryEntry& entry, const char* what);
  // Undo / redo of an author's entry (undo(author)): the whole swap or the entry's own part (see undo()).
  std::uint64_t swap_own(HistoryEntry& entry, bool undo);
  std::size_t history_limit() const;
  // Responses (session_response.cpp): the step is applied and detected; `before` is its image.
  // A merge makes `before` a whole image.
  void respond(const DeformParams& params, SessionImage& before, std::uint64_t version_before, StepResult& out);
  // Applies `params` (restored state) and detects; the core of deform() and of back-off.
  // `previous_done`: the caller has already copied the deformable rows into the tool's `previous`
  // (only when previous_current(); deform() does it in the before-image's pass).
  void step_once(const DeformParams& params, StepResult& out, bool previous_done = false);
  // The acting tool's `previous` differs from the model on its deformable rows only (nothing but its
  // last completed step changed the model since it was taken), so a step need copy only those rows.
  bool previous_current() const;
  // Puts `before` back after a step failed part-way (an unsaved detector is rebuilt from the restored
  // model) and the version to `version_before`.
  void roll_back(SessionImage& before, std::uint64_t version_before);
  // Merge without the history entry (session_merge.cpp); the core of merge() and of response "merge".
  MergeOutcome merge_now(bool crease);
  // The detector for `settings` (make_detector), reset from the model as it is now (null for none).
  std::shared_ptr<CollisionDetector> fresh_detector(const SessionSettings& settings,
                                                    const DeformationFields& fields) const;
  // The merge origins from the model as it is now (whenever the detector is reset).
  void take_origins();
  // Removes the rows with keep[r] false from the model and every per-row array (validated by the caller).
  void remove_rows(const IdList& ids, const std::vector<bool>& keep);
  // Conflict (naming `field`) when keeping only the rows with keep[r] leaves a tool's zero or one region empty.
  void check_regions_kept(const std::vector<bool>& keep, const char* field) const;
  // Rows appended to the model (the last parents.size() rows), each inheriting its parent row's
  // region and fields (in every tool with regions) and rest radius; their row versions are the current
  // version. `skip_acting`: the acting tool's fields were extended already (resampling's splits).
  void extend_rows(const IndexList& parents, bool skip_acting = false);

  std::string name_;
  SessionParams params_;
  std::uint64_t version_ = 0;
  std::uint64_t model_version_ = 0;         // version at which the current model was loaded
  SurfelModel model_;
  RowVersions row_version_;                 // per row: version of its last change (4 B, row_versions.hpp)
  std::vector<std::pair<std::uint64_t, SurfelId>> removed_log_;
  Values rest_radius_;  // per row, for resampling (built when a tool enables resampling)
  std::map<std::string, Tool> tools_;  // by author ("" the default tool); nodes are stable
  Tool* tool_ = nullptr;               // the acting tool (use()); rows images restore into their own
  std::string tool_id_;                // its author
  HistoryParams history_params_;       // the history bound (setting history_mb), the session's
  History history_;
};

}  // namespace surfeledit
