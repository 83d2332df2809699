// Sphere cluster trees from hierarchical clustering and from region growing: every node encloses its
// children's spheres and its surfels' balls; the layout is the Bvh one (children adjacent, ranges);
// the leaves are the clusters; build times printed.
#include <gtest/gtest.h>

#include <cstdio>

#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/simplify/clustering.hpp"
#include "surfeledit/core/simplify/sphere_tree.hpp"

namespace surfeledit {
namespace {

TEST(SphereTree, NodesEncloseChildrenAndSurfels) {
  const SampledSurfels s = make_cup()->sample(SampleParams{0.03, 1, 0.25});
  const Index n = static_cast<Index>(s.positions.rows());
  IndexList rows;
  for (Index r = 0; r < n; r += 3) rows.push_back(r);  // a subset
  for (int size : {1, 2, 18, 60}) {
    SimplifyParams p;
    p.cluster_size = size;
    p.threads = 2;
    for (bool hierarchical : {true, false}) {
      const SphereClusterTree t = hierarchical ? SphereClusterTree::build_hierarchical(s.positions, s.radii, rows, p)
                                               : SphereClusterTree::build_region_growing(s.positions, s.radii, rows, p);
      ASSERT_FALSE(t.empty());
      EXPECT_NO_THROW(t.check(s.positions, s.radii));
      // order() is a permutation of the rows.
      IndexList sorted = t.order();
      std::sort(sorted.begin(), sorted.end());
      EXPECT_EQ(sorted, rows);
      const Clustering c = hierarchical ? cluster_hierarchical(s.positions, rows, p) : cluster_region_growing(s.positions, rows, p);
      EXPECT_EQ(t.leaf_count(), c.size());
      EXPECT_EQ(static_cast<std::size_t>(2 * t.leaf_count() - 1), t.nodes().size());  // a full binary tree
      std::printf("[ sphere tree ] %s size %d: %zu surfels, %d leaves, height %d, root r %.3f, %.1f ms\n",
                  hierarchical ? "hierarchical  " : "region growing", size, rows.size(), t.leaf_count(), t.height(),
                  t.nodes()[0].sphere.radius, t.build_ms());
    }
  }
}

TEST(SphereTree, EmptyAndSingle) {
  const SampledSurfels s = make_sphere(1.0)->sample(SampleParams{0.2, 1, 0.25});
  SimplifyParams p;
  EXPECT_TRUE(SphereClusterTree::build_hierarchical(s.positions, s.radii, {}, p).empty());
  EXPECT_TRUE(SphereClusterTree::build_region_growing(s.positions, s.radii, {}, p).empty());
  const SphereClusterTree one = SphereClusterTree::build_region_growing(s.positions, s.radii, {5}, p);
  ASSERT_EQ(one.nodes().size(), 1u);
  EXPECT_NEAR(one.nodes()[0].sphere.radius, s.radii[5], 1e-12);
}

}  // namespace
}  // namespace surfeledit
