// The zero tree of a hierarchical detector (zero_tree.hpp).
#include "zero_tree.hpp"

#include <utility>
#include <vector>

#include "surfeledit/core/simplify/sphere_tree.hpp"

namespace surfeledit::detail {

ZeroTree build_zero_tree(const CollisionScene& scene, const IndexList& zero_rows, const HierarchyParams& h) {
  switch (h.zero) {
    case ZeroHierarchy::Obb: return ZeroTree(std::in_place_index<1>, scene.positions, scene.radii, zero_rows, h.tree);
    case ZeroHierarchy::Sphere:
      return ZeroTree(std::in_place_index<2>, scene.positions, scene.radii, zero_rows, h.tree);
    case ZeroHierarchy::SphereHierarchical:
    case ZeroHierarchy::SphereIncremental: {
      const SphereClusterTree clusters =
          h.zero == ZeroHierarchy::SphereHierarchical
              ? SphereClusterTree::build_hierarchical(scene.positions, scene.radii, zero_rows, h.clusters)
              : SphereClusterTree::build_region_growing(scene.positions, scene.radii, zero_rows, h.clusters);
      // Same layout as a Bvh: copy the nodes and let the tree derive its leaf map and step arrays.
      std::vector<bvh::BvhNode<bvh::Sphere>> nodes;
      nodes.reserve(clusters.nodes().size());
      for (const SphereTreeNode& c : clusters.nodes()) {
        bvh::BvhNode<bvh::Sphere> n;
        n.box = c.sphere;
        n.first_child = c.first_child;
        n.parent = c.parent;
        n.begin = c.begin;
        n.end = c.end;
        n.level = c.level;
        nodes.push_back(n);
      }
      ZeroTree tree(std::in_place_index<2>);
      std::get<2>(tree).adopt(std::move(nodes), clusters.order(), h.tree);
      return tree;
    }
    case ZeroHierarchy::Aabb:
    case ZeroHierarchy::None: break;
  }
  return ZeroTree(std::in_place_index<0>, scene.positions, scene.radii, zero_rows, h.tree);
}

}  // namespace surfeledit::detail
