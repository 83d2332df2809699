// Sphere cluster trees (docs/algorithms.md §6, thesis §9.4): a binary sphere hierarchy whose leaves are the
// clusters of a simplification.
//  - From hierarchical clustering the binary split tree is given; each leaf gets the minimal enclosing
//    sphere of its surfels' balls (position, radius), each inner node the minimal sphere enclosing its
//    two children's spheres (so it encloses its children and hence all its surfels).
//  - From region growing (bottom-up, "incremental"): the clusters are the leaves; their sphere centres
//    are clustered again by region growing (k = cluster_size, at least 2) until one cluster is left,
//    which gives a k-ary tree; each k-ary node is made binary by repeatedly merging the two children
//    whose merged (minimal enclosing) sphere is smallest (Huffman-like, O(k^2) per node with a table of
//    pairwise merged radii).
//
// Layout (the same as bvh::Bvh's, so the tree can be adopted as a Bvh<bvh::Sphere> zero hierarchy):
// nodes in one flat array, root = 0, the two children of a node adjacent (first_child, first_child + 1)
// and after it; every node covers the slots [begin, end) of order(), a permutation of the tree's rows.
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/bvh/sphere.hpp"
#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {

struct SphereTreeNode {
  bvh::Sphere sphere;             // encloses the balls of all surfels under the node and its children's spheres
  std::int32_t first_child = -1;  // left child, the right one is first_child + 1; -1 = leaf (a cluster)
  std::int32_t parent = -1;       // -1 for the root
  std::int32_t begin = 0;         // first slot of order() under this node
  std::int32_t end = 0;           // one past the last slot
  std::int32_t level = 0;         // depth, root = 0
  std::int32_t size() const { return end - begin; }  // surfels under the node
};

class SphereClusterTree {
 public:
  const std::vector<SphereTreeNode>& nodes() const { return nodes_; }
  const IndexList& order() const { return order_; }  // rows of the tree, grouped by leaf
  bool empty() const { return nodes_.empty(); }
  Index leaf_count() const;                           // clusters
  int height() const;                                 // levels (0 when empty)
  double build_ms() const { return build_ms_; }       // wall time of the build (clustering included)
  double cluster_ms() const { return cluster_ms_; }   // of which the leaf clustering
  // Throws Internal naming the node if a node's sphere misses a child's sphere or one of its surfels'
  // balls, or the layout is broken (ranges, children adjacency).
  void check(const Points& positions, const Values& radii) const;

  // Builds from hierarchical clustering / from region growing (see above) over `rows`; `radii` may be
  // empty (radius 0). params.method is ignored; cluster_size and max_variation apply to the leaves.
  static SphereClusterTree build_hierarchical(const Points& positions, const Values& radii, const IndexList& rows,
                                              const SimplifyParams& params);
  static SphereClusterTree build_region_growing(const Points& positions, const Values& radii,
                                                const IndexList& rows, const SimplifyParams& params);

 private:
  std::vector<SphereTreeNode> nodes_;
  IndexList order_;
  double build_ms_ = 0.0;
  double cluster_ms_ = 0.0;
  friend struct SphereTreeBuilder;
};

}  // namespace surfeledit
