// The tree over a hierarchical detector's zero rows (hierarchical_detector.hpp): AABB, OBB or sphere boxes
// in one variant, so a step dispatches once (std::visit) rather than per node.
#pragma once

#include <variant>

#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/bvh/obb.hpp"
#include "surfeledit/core/bvh/sphere.hpp"
#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/hierarchy.hpp"

namespace surfeledit::detail {

using ZeroTree = std::variant<bvh::Bvh<bvh::Aabb>, bvh::Bvh<bvh::Obb>, bvh::Bvh<bvh::Sphere>>;

// The tree of `h.zero` over the balls (position, radius) of `zero_rows` (AABB for Aabb and None); sphere
// cluster trees are built by simplify/sphere_tree.hpp and adopted in a Bvh's layout.
ZeroTree build_zero_tree(const CollisionScene& scene, const IndexList& zero_rows, const HierarchyParams& h);

}  // namespace surfeledit::detail
