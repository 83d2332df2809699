// Clustering (region growing, hierarchical): each surfel in exactly one cluster; hierarchical clusters
// respect the size bound (and the variation bound); region growing yields about n / k clusters; a
// cluster's simplified surfel lies within its members' bounding box; the surfel -> cluster map follows
// insertion (children join their parent's cluster) and removal.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/simplify/cluster_map.hpp"
#include "surfeledit/core/simplify/simplified_surfel.hpp"
#include "surfeledit/core/simplify/surface_variation.hpp"

namespace surfeledit {
namespace {

SampledSurfels torus() { return make_torus(1.0, 0.35)->sample(SampleParams{0.04, 3, 0.25}); }

IndexList every_other(Index n) {
  IndexList r;
  for (Index i = 0; i < n; i += 2) r.push_back(i);
  return r;
}

void expect_partition(const Clustering& c, const IndexList& rows, Index total) {
  std::vector<int> seen(static_cast<std::size_t>(total), 0);
  ASSERT_EQ(c.offsets.front(), 0);
  ASSERT_EQ(c.offsets.back(), static_cast<std::int64_t>(c.members.size()));
  for (Index k = 0; k < c.size(); ++k) {
    EXPECT_GT(c.count(k), 0);
    for (Index j = 0; j < c.count(k); ++j) ++seen[c.rows(k)[j]];
  }
  std::vector<int> want(static_cast<std::size_t>(total), 0);
  for (Index r : rows) want[r] = 1;
  EXPECT_EQ(seen, want);
}

SimplifyParams clustering_params(SimplifyMethod m, int size, double max_variation = 1.0) {
  SimplifyParams p;
  p.method = m;
  p.cluster_size = size;
  p.max_variation = max_variation;
  return p;
}

TEST(Clustering, EverySurfelInExactlyOneCluster) {
  const SampledSurfels s = torus();
  const Index n = static_cast<Index>(s.positions.rows());
  for (const IndexList& rows : {every_other(n), IndexList{}}) {
    for (auto m : {SimplifyMethod::None, SimplifyMethod::RegionGrowing, SimplifyMethod::Hierarchical}) {
      for (int size : {1, 2, 18, 100}) {
        const Clustering c = make_clusters(s.positions, rows, clustering_params(m, size));
        expect_partition(c, rows, n);
        if (m == SimplifyMethod::None || size == 1) EXPECT_EQ(c.size(), static_cast<Index>(rows.size()));
      }
    }
  }
}

TEST(Clustering, DuplicatePositions) {
  Points p(60, 3);
  for (Index i = 0; i < 60; ++i) p.row(i) = Vec3(i % 3, 0, 0).transpose();  // 3 positions, 20 copies each
  IndexList rows(60);
  for (Index i = 0; i < 60; ++i) rows[i] = i;
  for (auto m : {SimplifyMethod::RegionGrowing, SimplifyMethod::Hierarchical}) {
    const Clustering c = make_clusters(p, rows, clustering_params(m, 7));
    expect_partition(c, rows, 60);
    if (m == SimplifyMethod::Hierarchical)
      for (Index k = 0; k < c.size(); ++k) EXPECT_LE(c.count(k), 7);
  }
}

TEST(Clustering, HierarchicalRespectsTheBounds) {
  const SampledSurfels s = torus();
  const Index n = static_cast<Index>(s.positions.rows());
  IndexList rows(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) rows[i] = i;
  for (int size : {1, 10, 18, 100}) {
    const Clustering c = cluster_hierarchical(s.positions, rows, clustering_params(SimplifyMethod::Hierarchical, size));
    for (Index k = 0; k < c.size(); ++k) ASSERT_LE(c.count(k), size);
    EXPECT_GE(c.size(), n / size);
    // The split tree: leaves are the clusters, children cover their parent's range.
    for (const ClusterTreeNode& node : c.tree) {
      if (node.first_child < 0) {
        ASSERT_GE(node.cluster, 0);
        EXPECT_EQ(c.offsets[node.cluster], node.begin);
        EXPECT_EQ(c.offsets[node.cluster + 1], node.end);
      } else {
        EXPECT_EQ(c.tree[node.first_child].begin, node.begin);
        EXPECT_EQ(c.tree[node.first_child].end, c.tree[node.first_child + 1].begin);
        EXPECT_EQ(c.tree[node.first_child + 1].end, node.end);
      }
    }
  }
  // With a variation bound: every cluster is flat enough, so a curved torus gets more clusters.
  const Clustering loose = cluster_hierarchical(s.positions, rows, clustering_params(SimplifyMethod::Hierarchical, 100));
  const Clustering flat = cluster_hierarchical(s.positions, rows, clustering_params(SimplifyMethod::Hierarchical, 100, 0.01));
  for (Index k = 0; k < flat.size(); ++k) {
    ASSERT_LE(flat.count(k), 100);
    EXPECT_LE(surface_variation(s.positions, flat.rows(k), static_cast<std::size_t>(flat.count(k))), 0.01);
  }
  EXPECT_GT(flat.size(), loose.size());
  std::printf("[ hierarchical ] %d surfels, size 100: %d clusters; with sigma_max 0.01: %d\n", n, loose.size(), flat.size());
}

TEST(Clustering, RegionGrowingMakesAboutNOverKClusters) {
  const SampledSurfels s = torus();
  const Index n = static_cast<Index>(s.positions.rows());
  IndexList rows(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) rows[i] = i;
  for (int size : {10, 18, 100}) {
    const Clustering c = cluster_region_growing(s.positions, rows, clustering_params(SimplifyMethod::RegionGrowing, size));
    const double mean = static_cast<double>(n) / c.size();
    std::printf("[ region growing ] %d surfels, k = %d: %d clusters, mean %.1f\n", n, size, c.size(), mean);
    for (Index k = 0; k < c.size(); ++k) EXPECT_GE(c.count(k), size);  // k taken, strays only add
    EXPECT_LT(mean, 2.0 * size);
  }
  // A variation bound makes clusters smaller where the surface bends.
  const Clustering bounded = cluster_region_growing(s.positions, rows, clustering_params(SimplifyMethod::RegionGrowing, 100, 0.005));
  const Clustering free = cluster_region_growing(s.positions, rows, clustering_params(SimplifyMethod::RegionGrowing, 100));
  EXPECT_GT(bounded.size(), free.size());
}

TEST(Clustering, SimplifiedSurfelLiesInItsMembersBoundingBox) {
  const SampledSurfels s = torus();
  const Index n = static_cast<Index>(s.positions.rows());
  IndexList rows(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) rows[i] = i;
  for (auto m : {SimplifyMethod::RegionGrowing, SimplifyMethod::Hierarchical}) {
    const Clustering c = make_clusters(s.positions, rows, clustering_params(m, 18));
    const std::vector<SimplifiedSurfel> simple = simplify(s.positions, s.normals, s.radii, c, 2);
    ASSERT_EQ(static_cast<Index>(simple.size()), c.size());
    for (Index k = 0; k < c.size(); ++k) {
      Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
      for (Index j = 0; j < c.count(k); ++j) {
        const Index r = c.rows(k)[j];
        lo = lo.cwiseMin(s.positions.row(r).transpose());
        hi = hi.cwiseMax(s.positions.row(r).transpose());
        // Its radius covers each member's disc.
        EXPECT_LE((s.positions.row(r).transpose() - simple[k].position).norm() + s.radii[r], simple[k].radius * (1 + 1e-12));
        EXPECT_GT(simple[k].normal.dot(s.normals.row(r).transpose()), 0.0);  // small clusters: normals agree
      }
      const double eps = 1e-12 * (1.0 + hi.cwiseAbs().maxCoeff());
      EXPECT_TRUE((simple[k].position.array() >= lo.array() - eps).all() && (simple[k].position.array() <= hi.array() + eps).all());
      EXPECT_NEAR(simple[k].normal.norm(), 1.0, 1e-12);
      EXPECT_EQ(simple[k].count, c.count(k));
    }
  }
}

TEST(ClusterMap, InsertionJoinsTheParentRemovalLeaves) {
  const SampledSurfels s = torus();
  const Index n = static_cast<Index>(s.positions.rows());
  const IndexList rows = every_other(n);  // odd rows are in no cluster (like zero surfels)
  ClusterMap map(n, cluster_hierarchical(s.positions, rows, clustering_params(SimplifyMethod::Hierarchical, 18)));
  map.check();
  EXPECT_EQ(map.cluster_of(1), -1);
  const IndexList parents{0, 2, 1, 0};
  const Index c0 = map.cluster_of(0), c2 = map.cluster_of(2);
  map.on_inserted(parents);
  map.check();
  EXPECT_EQ(map.rows(), n + 4);
  EXPECT_EQ(map.cluster_of(n), c0);
  EXPECT_EQ(map.cluster_of(n + 1), c2);
  EXPECT_EQ(map.cluster_of(n + 2), -1);
  EXPECT_EQ(map.cluster_of(n + 3), c0);
  // Remove row 0 and every row of cluster c2: c2 becomes empty, the rest is renumbered.
  std::vector<bool> keep(static_cast<std::size_t>(n + 4), true);
  keep[0] = false;
  for (Index r : map.members(c2)) keep[r] = false;
  const Index before = map.cluster_count();
  map.on_removed(keep);
  map.check();
  EXPECT_EQ(map.cluster_count(), before);
  EXPECT_TRUE(map.members(c2).empty());
  EXPECT_EQ(map.cluster_of(map.rows() - 1), c0);  // the last child of row 0 survives, still in c0
}

}  // namespace
}  // namespace surfeledit
