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

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/selector.hpp"
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
  // Applies one step; requires regions. Bumps the version.
  DeformResult deform(const DeformParams& params);

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
};

}  // namespace surfeledit
