// Collision detection between the deformable part of a model and its zero region (§4 of
// docs/algorithms.md; thesis ch. 6): four algorithms behind one interface.
//
// A deformable surfel s1 (position p1) with nearest reference surfel s2 (p2, normal n2) is
// *inside* when (p1 - p2) . n2 < W (strict; W = `threshold`, 0 by default). The reference set is
// the zero region (Simple, Improved, Temporal) or the original, undeformed whole model (Robust).
// All distances in model units; `dist2` / `rho2` are squared.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/hierarchy.hpp"

namespace surfeledit {

enum class CollisionAlgorithm : std::uint8_t {
  None = 0,      // no detection (nothing built)
  Simple = 1,    // §4.1: nearest zero surfel of every deformable surfel, every step
  Improved = 2,  // §4.2: Simple + spatial coherence (a tested ball settles its deformable surfels)
  Temporal = 3,  // §4.3: Simple + temporal coherence (a surfel inside its sphere keeps its state)
  Robust = 4,    // §4.4: parity of inside changes against the original model (the default)
};

constexpr EnumNames<CollisionAlgorithm, 5> names_of(CollisionAlgorithm) {
  return {{{CollisionAlgorithm::None, "none"},
           {CollisionAlgorithm::Simple, "simple"},
           {CollisionAlgorithm::Improved, "improved"},
           {CollisionAlgorithm::Temporal, "temporal"},
           {CollisionAlgorithm::Robust, "robust"}}};
}
// Throws InvalidArgument naming `field` for a name not in names_of.
inline CollisionAlgorithm parse_algorithm(const std::string& name, const std::string& field = "algorithm") {
  return parse_enum<CollisionAlgorithm>(name, field);
}
inline const char* to_string(CollisionAlgorithm algorithm) { return enum_name(algorithm); }

// How Temporal and Robust decide that a point is inside the rigid solid (§4.6 of docs/algorithms.md).
enum class InsideMode : std::uint8_t {
  Nearest = 0,  // the thesis's test against one nearest reference surfel (§4.3, §4.4)
  Winding = 1,  // generalized winding number of the zero region > 1/2 (fast dipole tree)
  Vote = 2,     // the k nearest zero surfels vote, weighted by distance and normal agreement
};
constexpr EnumNames<InsideMode, 3> names_of(InsideMode) {
  return {{{InsideMode::Nearest, "nearest"}, {InsideMode::Winding, "winding"}, {InsideMode::Vote, "vote"}}};
}

struct CollisionParams {
  CollisionAlgorithm algorithm = CollisionAlgorithm::Robust;  // which detector
  double threshold = 0.0;        // W: inside iff (p1 - p2) . n2 < W, model units
  bool boundary = true;          // Simple/Improved/Temporal: the boundary-surfel heuristic (§4.1)
  int boundary_n = 10;           // neighbours (whole model) looked at per deformable surfel, >= 1
  int boundary_i = 5;            // of those, the i nearest zero surfels are marked boundary, 1..n
  bool step_bound = true;        // Simple/Improved/Temporal: state may change only if |d| <= |t| + r1 + r2
  double sphere_margin = 0.5;    // Temporal/Robust: a sphere's radius is |d| - margin * r2 (r2: radius of the
                                 // nearest surfel), so it stays clear of that surfel's disc; 0 = the thesis's |d|
  int threads = 0;               // worker threads (0 = all); results do not depend on it
  double parallel_min_ms = 1.0;  // a step's row loop runs on several threads only when its estimated one-thread
                                 // work (from the previous step's queries) is at least this, ms; 0 = whenever
                                 // threads > 1; results do not depend on it (row_detector.hpp ParallelSweep)
  double knn_eps = 0.0;          // approximate nearest-surfel queries (the k-d tree's eps, >= 0): the surfel found
                                 // is at most sqrt(1 + eps) x as far as the nearest one; 0 = exact (default)
  InsideMode inside = InsideMode::Nearest;  // Temporal/Robust: the inside test of a tested point (§4.6)
  double winding_beta = 2.0;     // winding: far-field acceptance of the dipole tree (0 = exact sums), >= 0
  int vote_k = 8;                // vote: zero surfels that vote, >= 1
  bool swept = false;            // Temporal/Robust: a point whose step passed through the rigid solid is
                                 // reported colliding in that step (no tunnelling, §4.7)
};

// Throws InvalidArgument naming the field (e.g. "boundary_n") and the value.
void validate(const CollisionParams& params);

struct CollisionStats {
  Index deformable = 0;      // deformable surfels considered this step
  Index tested = 0;          // surfels whose state was (re)evaluated this step
  Index queries = 0;         // nearest-neighbour queries made this step
  Index colliding = 0;       // surfels reported colliding
  double detect_ms = 0.0;    // time of this step's detection
  double preprocess_ms = 0.0;  // time of the last reset (building trees, spheres, boundary marks)
  Index nv = 0;              // hierarchies: bounding-volume overlap tests this step (Eq. 8.11); 0 without
  Index np = 0;              // hierarchies: candidates handed to the narrow phase this step; 0 without
  Index nu = 0;              // hierarchies: boxes updated this step (refit, insertion); 0 without
  Index asleep = 0;          // deformable surfels of sleeping blocks this step: not read, their states provably
                             // unchanged (a step with a displacement bound; Robust and Temporal rows; RESULTS §84)
};

struct CollisionResult {
  IndexList colliding;         // rows of colliding surfels, ascending
  std::vector<double> depths;  // per colliding row: penetration depth estimate (>= 0, model units)
  CollisionStats stats;
};

// The model as a detector sees it. Arrays have #P rows; `regions` from the deformation fields.
struct CollisionScene {
  const Points& positions;             // #P by 3, current
  const Points& normals;               // #P by 3, current, unit
  const Values& radii;                 // #P
  const std::vector<Region>& regions;  // #P; deformable = not Zero
  // For detect() only: an upper bound on |position - previous| of every deformable row (model units, finite,
  // >= 0) together with the promise that no deformable radius changed since this detector's last detect()
  // or reset(); the deformation step knows it (displacement_bound(DeformParams)). Empty: the detector
  // measures both itself (a pass over the deformable rows). The hierarchies read it (a debug build checks it
  // against the measured value), and so do the Robust and Temporal row sweeps: rows that stay that far inside
  // their spheres are not read (sleeping blocks; a checked build checks each of them). Refused
  // (InvalidArgument) when negative or not finite.
  std::optional<double> displacement_bound{};
};

// Rigid rows as a detector last saw them, before another tool's ops moved them (on_rigid_moved): one entry
// per moved row, in the order of the row list that comes with it.
struct RigidRows {
  Points positions;  // #rows by 3
  Points normals;    // #rows by 3, unit
  Values radii;      // #rows
  void resize(Eigen::Index rows) {  // all three arrays to `rows` (values unset)
    positions.resize(rows, 3);
    normals.resize(rows, 3);
    radii.resize(rows);
  }
};

// What a detector's hierarchies look like now.
struct HierarchyInfo {
  std::string status;              // "fresh" | "refit" | "rebuilding" (deformable tree; "fresh" for a zero
                                   // tree alone, which is never refit); "" without a hierarchy
  double zero_build_ms = 0.0;      // build of the zero tree at the last reset
  double deformable_build_ms = 0.0;  // build of the deformable tree at the last reset (0 without one)
  double last_rebuild_ms = 0.0;    // the last background rebuild that finished (0 before any)
  Index rebuilds_adopted = 0;      // background rebuilds swapped in since the last reset
};

struct SessionSettings;
class SnapshotWriter;
class SnapshotReader;

// What one detect() changes in a detector (per-row states, the step's tallies), saved for undo
// (history.hpp). Opaque; only the detector that saved it reads it.
struct DetectorImage {
  virtual ~DetectorImage() = default;
  virtual std::size_t bytes() const = 0;  // memory held
};

class CollisionDetector {
 public:
  // A detector for `params.algorithm` (nullptr for None). Validates params (and `hierarchy`); with
  // hierarchy.zero != None the detector runs that broad phase before the algorithm's narrow test.
  static std::unique_ptr<CollisionDetector> create(const CollisionParams& params,
                                                   const HierarchyParams& hierarchy = {});
  virtual ~CollisionDetector() = default;

  const CollisionParams& params() const { return params_; }

  // (Re)initialises every state from the model as it is now: this becomes the "original"
  // model (Robust), spheres start at the current positions, nothing collides. Records
  // stats().preprocess_ms.
  virtual void reset(const CollisionScene& scene) = 0;
  // Evaluates the model after a step. `previous`: positions before the step (#P by 3), for each
  // surfel's own displacement t. Zero surfels must not have moved since reset.
  virtual CollisionResult detect(const CollisionScene& scene, const Points& previous) = 0;
  // detect() re-testing only rows with candidate[r] != 0 (one flag per row); the result lists only
  // those rows, the others' states are not touched (row detectors). For back-off's re-tests of the
  // surfels that collided (§7 c). The default ignores `candidate` and runs detect().
  virtual CollisionResult detect_only(const CollisionScene& scene, const Points& previous,
                                      const std::vector<std::uint8_t>& candidate);
  // Rows removed from the model: `keep` has one flag per old row; state of kept rows is compacted.
  virtual void on_removed(const std::vector<bool>& keep) = 0;
  // Rows appended to the model (after the existing ones), each split from `parents[k]` (a row
  // before the append). A child inside its parent's sphere takes the parent's sphere and state;
  // otherwise it starts with radius 0 (tested at the next step) (§4.4, thesis §6.5).
  virtual void on_inserted(const CollisionScene& scene, const IndexList& parents) = 0;
  // Rows the detector treats as rigid (Zero in `scene.regions`) changed under it: another tool's op moved
  // them (issue 11 §1, docs/collaboration.md). `rows`: ascending model rows, every one Zero, the row count
  // the same as at reset; `scene` holds their positions, normals and radii now, `before` (one entry per row
  // of `rows`) what they were when this detector last saw them (the caller keeps them: Robust reads its
  // zero rows from the model and keeps no copy of them). Updates the references (zero copies and their
  // tree; Robust: the original model's tree) for these rows only and empties every sphere that now holds
  // one of them (its point is tested at the next step); other states are kept.
  // False (nothing changed) when this detector cannot follow incrementally: the caller resets it. The row
  // detectors (Simple, Improved, Temporal, Robust) with the nearest inside test can; hierarchies, approximate
  // detection, inside modes winding and vote, and the swept test cannot (the default).
  virtual bool on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& before);
  // The deformable rows' positions and normals as the last reset() saw them (#D by 3 each, in ascending row
  // order), when this detector keeps them unchanged until its next reset (Robust's original model; removals,
  // insertions, rigid moves, detections and image restores leave them as they are; clones and snapshots hold
  // the same values). Both null otherwise (the default). The session's merge origins read them instead of a
  // copy of their own (MergeMemo::origins_in_detector).
  struct ResetRows {
    const Points* positions = nullptr;
    const Points* normals = nullptr;
  };
  virtual ResetRows reset_rows() const { return {}; }
  // Bytes held (trees, per-surfel state).
  virtual std::size_t memory_bytes() const = 0;
  // What it holds, by name, for a session report (default: one entry "collision_<algorithm>").
  virtual std::vector<std::pair<std::string, std::size_t>> structures() const;

  // Hierarchies only: starts a background rebuild of the deformable tree from the model as it is
  // now; the next detect() that finds it finished adopts it. Never waits. False when there is no
  // deformable tree or a rebuild is already under way.
  virtual bool start_rebuild(const CollisionScene& scene);
  // State of the hierarchies (all empty / zero without one).
  virtual HierarchyInfo hierarchy_info() const;

  // Undo support. save_image(): what detect() may change, nullptr when this detector cannot save it.
  // restore_image(): puts back an image this detector saved,
  // with the rows it had then (Internal otherwise). clone(): an independent deep copy whose every
  // later result equals this one's, nullptr when not supported.
  // `rows` (ascending deformable rows): save only those (nullptr: every deformable row).
  virtual std::shared_ptr<const DetectorImage> save_image(const IndexList* rows = nullptr) const;
  virtual void restore_image(const DetectorImage& image);
  virtual std::unique_ptr<CollisionDetector> clone() const;
  // The journal: a cheaper before-image of a step, for the detectors that keep one (row detectors with
  // independent points). start_journal(): from now on, every row whose state a detect() / detect_only()
  // changes keeps its state from this moment (first change wins), and rows re-evaluated with a query are
  // noted; false when states are not kept this time (then save_image() before the step; the tested rows
  // may still be noted). journal_image(): those rows and states, an image restore_image() takes (nullptr
  // when no states are kept). stop_journal(): ends it. Reset, removal and insertion end it.
  virtual bool start_journal();
  virtual std::shared_ptr<const DetectorImage> journal_image() const;
  // restore_journal(): puts back the journal's states, as restore_image(*journal_image()) would, without
  // building the image (Internal when no journal runs).
  virtual void restore_journal();
  // journal_tested(): sets flags[r] (one per row) for every row whose state a detection since
  // start_journal() re-evaluated with a query (the others stayed inside their empty spheres); false
  // (flags untouched) without a journal.
  virtual bool journal_tested(std::vector<std::uint8_t>& flags) const;
  virtual void stop_journal();

  // Snapshots (docs/journal.md; detector_snapshot.hpp writes a detector with its params): the structures
  // themselves, never a rebuild from the model, so that every later result equals this detector's.
  // snapshottable(): whether this detector can (false: the default; the session falls back to log replay).
  // save_state() / load_state(): everything but the params (load_state() on a detector made for the same
  // params; validates sizes and rows, InvalidArgument "snapshot" otherwise). save_image_state() /
  // load_image_state(): a DetectorImage this detector type saved.
  virtual bool snapshottable() const;
  virtual void save_state(SnapshotWriter& out) const;
  virtual void load_state(SnapshotReader& in);
  virtual void save_image_state(SnapshotWriter& out, const DetectorImage& image) const;
  virtual std::shared_ptr<const DetectorImage> load_image_state(SnapshotReader& in) const;

 protected:
  explicit CollisionDetector(CollisionParams params) : params_(params) {}
  CollisionParams params_;
};

// The detector `settings` ask for, not yet reset (nullptr for algorithm none): the approximate
// detector on clusters when settings.simplify.method != None (simplify/approximate_detector.hpp),
// else CollisionDetector::create(settings.collision, settings.hierarchy). The collision thread count
// also drives the clustering, whose parameters also shape sphere cluster trees. Validates.
std::unique_ptr<CollisionDetector> make_detector(const SessionSettings& settings);

}  // namespace surfeledit
