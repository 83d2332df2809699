// Bounding volume hierarchies of a collision detector (docs/algorithms.md §5; thesis ch. 7-8): which trees a
// session builds and how, chosen per session by name (settings.hpp).
//
// With a hierarchy the detector runs a broad phase first: a deformable surfel is a *candidate* when
// its ball (position, radius + its own displacement this step) overlaps a zero leaf box (surfel/tree)
// or lies in a deformable leaf whose box overlaps a zero leaf box (tree/tree). Only candidates get the
// configured algorithm's narrow test (the same code as without a hierarchy); the others keep their
// collision state. A surfel whose ball reaches no zero surfel ball cannot have crossed the zero
// surface this step, which is exactly the step bound of Simple/Temporal (§4.1), so those give the
// same colliding set as without a hierarchy by construction; for Robust see src/bvh/hierarchical_detector.hpp.
#pragma once

#include <cstdint>
#include <string>

#include "surfeledit/core/bvh/overlap.hpp"
#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/bvh/params.hpp"
#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {

struct CollisionParams;

// Box kind of the tree over the zero region: a top-down Bvh, or a sphere cluster tree (docs/algorithms.md §6,
// simplify/sphere_tree.hpp) whose leaves are clusters of the zero surfels (HierarchyParams::clusters).
enum class ZeroHierarchy : std::uint8_t {
  None = 0,                // no hierarchy
  Aabb = 1,                // top-down tree of axis-aligned boxes
  Obb = 2,                 // top-down tree of oriented boxes
  Sphere = 3,              // top-down tree of spheres
  SphereHierarchical = 4,  // sphere cluster tree from hierarchical clustering (the split tree)
  SphereIncremental = 5,   // sphere cluster tree built bottom-up from region-growing clusters
};
// Box kind of the tree over the deformable region (AABB only: it is refit every step).
enum class DeformableHierarchy : std::uint8_t { None = 0, Aabb = 1 };

constexpr EnumNames<ZeroHierarchy, 6> names_of(ZeroHierarchy) {
  return {{{ZeroHierarchy::None, "none"},
           {ZeroHierarchy::Aabb, "aabb"},
           {ZeroHierarchy::Obb, "obb"},
           {ZeroHierarchy::Sphere, "sphere"},
           {ZeroHierarchy::SphereHierarchical, "sphere_hierarchical"},
           {ZeroHierarchy::SphereIncremental, "sphere_incremental"}}};
}
constexpr EnumNames<DeformableHierarchy, 2> names_of(DeformableHierarchy) {
  return {{{DeformableHierarchy::None, "none"}, {DeformableHierarchy::Aabb, "aabb"}}};
}
// Throw InvalidArgument naming `field` for a name not in names_of.
inline ZeroHierarchy parse_zero_hierarchy(const std::string& name, const std::string& field = "zero_hierarchy") {
  return parse_enum<ZeroHierarchy>(name, field);
}
inline DeformableHierarchy parse_deformable_hierarchy(const std::string& name,
                                                      const std::string& field = "deformable_hierarchy") {
  return parse_enum<DeformableHierarchy>(name, field);
}
inline const char* to_string(ZeroHierarchy kind) { return enum_name(kind); }
inline const char* to_string(DeformableHierarchy kind) { return enum_name(kind); }

struct HierarchyParams {
  ZeroHierarchy zero = ZeroHierarchy::None;                    // tree over the zero region (none = no hierarchy)
  DeformableHierarchy deformable = DeformableHierarchy::None;  // tree over the deformable region (needs `zero`)
  bvh::BvhParams tree;                                         // build and update parameters of both trees
  bvh::SatMode sat = bvh::SatMode::Lite;                       // OBB/AABB overlap test of tree/tree
  bool extended = false;  // narrow phase against the original model (§5 "Extended"); needs algorithm robust
  SimplifyParams clusters;  // sphere cluster trees: leaf clustering (cluster_size, max_variation; the session
                            // copies its simplify settings here); ignored by the other kinds

  bool any() const { return zero != ZeroHierarchy::None; }
};

// Throws InvalidArgument naming the offending setting: tree parameters (bvh::validate), a deformable
// tree without a zero tree, `extended` without a zero tree or with another algorithm than robust, and
// algorithms the broad phase cannot serve exactly (improved: its spatial coherence settles surfels
// from other surfels' queries; simple/temporal with step_bound off: a far surfel may still change).
void validate(const HierarchyParams& hierarchy, const CollisionParams& collision);

}  // namespace surfeledit
