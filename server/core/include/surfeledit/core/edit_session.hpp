// An editing session: one surfel model, its regions and deformation fields, a version
// counter, and the acceleration structures it needed so far (built lazily).
//
// Every mutating call validates everything first and throws before changing anything,
// so a failed request leaves the session exactly as it was. Not thread-safe: the owner
// serialises calls.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/selector.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct SessionParams {
  int threads = 0;  // worker threads for batch work; 0 = all hardware threads
};

// What changed since a given version.
struct Changes {
  bool full = false;  // the model was replaced since then: `changed` lists every surfel
  IdList changed;     // ids whose attributes changed (or that were inserted), ascending
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
};

// What one deformation step did.
struct StepResult {
  std::uint64_t seq = 0;       // 1-based step number in this session
  IndexList moved;             // rows whose attributes changed (moved or split), ascending
  IdList inserted;             // ids of surfels inserted by resampling (appended rows)
  Vec3 center = Vec3::Zero();  // rotation centre used
  bool detected = false;       // a collision detector ran
  IdList colliding;            // colliding surfel ids after the step, ascending
  std::vector<double> depths;  // per colliding id: penetration depth estimate, model units
  CollisionStats stats;        // of the detector (zeros when none ran)
  double deform_ms = 0.0;      // time of the deformation itself
  double resample_ms = 0.0;    // time of resampling
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
  bool has_regions() const { return fields_ != nullptr; }
  const DeformationFields* fields() const { return fields_.get(); }

  // Replaces the model; regions are cleared. Bumps the version.
  void load(SurfelModel model);
  // Resolves both specs, checks they are non-empty and disjoint, computes the deformation
  // fields. Surfels in neither region blend between them. Bumps the version.
  void set_regions(const RegionSpec& zero, const RegionSpec& one);
  // Ids matching a spec (ids validated, selectors applied to current positions), ascending.
  IdList resolve(const RegionSpec& spec, const std::string& field) const;
  // Applies one step, then resampling and collision detection as configured; requires regions.
  // Bumps the version.
  StepResult deform(const DeformParams& params);

  // Session settings (collision algorithm, heuristics, resampling); validated before anything
  // changes. Re-initialises the detector from the current model when regions are set (its
  // "original" model is the current one); the model and the version do not change.
  void configure(const std::vector<NamedSetting>& changes);
  const SessionSettings& settings() const { return settings_; }
  // Starts a background rebuild of the deformable tree from the model as it is now (rebuild on
  // idle, e.g. when a drag ends); the next step that finds it finished swaps it in. Never waits.
  // False when there is no deformable tree or a rebuild is under way.
  bool rebuild_hierarchies();
  // Status and build times of the detector's trees (empty without a hierarchy).
  HierarchyInfo hierarchy_info() const;
  // Colliding ids after the last step (empty before any step / after a reset), ascending.
  const IdList& colliding() const { return colliding_; }
  // Removes surfels (validated first: unknown ids, or leaving the zero or one region empty, throw
  // and change nothing); the detector keeps the state of the others. Bumps the version.
  void remove(const IdList& ids);

  // Changes since version `since` (since >= version() gives none).
  Changes changes_since(std::uint64_t since) const;
  SessionReport report() const;
  std::uint64_t state_hash() const;

 private:
  void touch_rows(const IndexList& rows);

  std::string name_;
  SessionParams params_;
  std::uint64_t version_ = 0;
  std::uint64_t model_version_ = 0;         // version at which the current model was loaded
  SurfelModel model_;
  std::vector<std::uint64_t> row_version_;  // per row: version of its last change
  std::vector<std::pair<std::uint64_t, SurfelId>> removed_log_;
  std::unique_ptr<DeformationFields> fields_;
  SessionSettings settings_;
  std::unique_ptr<CollisionDetector> detector_;  // built when regions are set and algorithm != none
  IdList colliding_;
  Values rest_radius_;  // per row, for resampling (built when resampling is enabled)
  std::uint64_t steps_ = 0;
};

}  // namespace surfeledit
