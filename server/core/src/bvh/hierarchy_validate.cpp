// Validation of a session's hierarchy settings against its collision settings (hierarchy.hpp).
#include <string>

#include "surfeledit/core/bvh/params.hpp"
#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/hierarchy.hpp"

namespace surfeledit {

void validate(const HierarchyParams& h, const CollisionParams& c) {
  bvh::validate(h.tree);
  if (h.zero == ZeroHierarchy::SphereHierarchical || h.zero == ZeroHierarchy::SphereIncremental) validate(h.clusters);
  if (h.zero > ZeroHierarchy::SphereIncremental) {
    throw Error(ErrorCode::InvalidArgument, "zero_hierarchy",
                "unknown zero hierarchy value " + std::to_string(static_cast<int>(h.zero)));
  }
  if (h.deformable > DeformableHierarchy::Aabb) {
    throw Error(ErrorCode::InvalidArgument, "deformable_hierarchy",
                "unknown deformable hierarchy value " + std::to_string(static_cast<int>(h.deformable)));
  }
  if (h.sat != bvh::SatMode::Lite && h.sat != bvh::SatMode::Full) {
    throw Error(ErrorCode::InvalidArgument, "sat", "unknown sat value " + std::to_string(static_cast<int>(h.sat)));
  }
  if (h.deformable != DeformableHierarchy::None && h.zero == ZeroHierarchy::None) {
    throw Error(ErrorCode::InvalidArgument, "deformable_hierarchy",
                std::string("deformable_hierarchy=") + to_string(h.deformable) +
                    " requires a zero_hierarchy (any but none): the deformable tree is tested against the zero tree");
  }
  if (h.extended && h.zero == ZeroHierarchy::None) {
    throw Error(ErrorCode::InvalidArgument, "extended", "extended=true requires a zero_hierarchy (any but none)");
  }
  if (!h.any() || c.algorithm == CollisionAlgorithm::None) return;
  if (h.extended && c.algorithm != CollisionAlgorithm::Robust) {
    throw Error(ErrorCode::InvalidArgument, "extended",
                std::string("extended=true tests against the original model as robust does: requires algorithm=robust, got ") +
                    to_string(c.algorithm));
  }
  if (c.algorithm == CollisionAlgorithm::Improved) {
    throw Error(ErrorCode::InvalidArgument, "zero_hierarchy",
                "algorithm=improved cannot run behind a hierarchy (its spatial coherence settles surfels from the "
                "queries of surfels the broad phase skips); use simple, temporal or robust, or zero_hierarchy=none");
  }
  if (!c.step_bound &&
      (c.algorithm == CollisionAlgorithm::Simple || c.algorithm == CollisionAlgorithm::Temporal)) {
    throw Error(ErrorCode::InvalidArgument, "zero_hierarchy",
                std::string("a hierarchy with algorithm=") + to_string(c.algorithm) +
                    " requires step_bound=true (the broad phase skips exactly the surfels the step bound keeps)");
  }
}

}  // namespace surfeledit
