// k-d tree exactness at the edges, against brute force: approximate search within eps, clouds at 1e6 offsets, exact
// ties in any query order and thread count, warm starts (from an identical query; nearest_within).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "kdtree_truth.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

using test::brute_dist2;
using test::expect_knn_matches;
using test::expect_radius_matches;
using test::random_cloud;

// Approximate search: eps = 0 is exact; eps > 0 returns, for each of the k slots, a neighbour whose squared
// distance is at most (1 + eps) x the true one's (hence its distance at most (1 + eps) x the true distance).
TEST(KdTree, ApproximateSearchWithinEpsOfBruteForce) {
  const Points pts = random_cloud(3000, 91);
  const Points queries = random_cloud(300, 92, 1.2);
  for (double eps : {0.0, 0.1, 0.5, 1.0, 2.0}) {
    KdTreeParams p;
    p.eps = eps;
    const KdTree tree(pts, p);
    const KdTree exact(pts);
    Index differing = 0;
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      const Vec3 x = queries.row(q).transpose();
      const std::vector<double> truth = brute_dist2(pts, x);
      double d2 = 0.0;
      const Index k = tree.nearest(x, &d2);
      ASSERT_GE(k, 0);
      EXPECT_NEAR(d2, (pts.row(k).transpose() - x).squaredNorm(), 1e-12);
      EXPECT_LE(d2, (1.0 + eps) * truth.front() * (1.0 + 1e-12) + 1e-15) << "eps " << eps;
      EXPECT_LE(std::sqrt(d2), (1.0 + eps) * std::sqrt(truth.front()) + 1e-12) << "eps " << eps;
      if (eps == 0.0) {
        double e2 = 0.0;
        EXPECT_EQ(k, exact.nearest(x, &e2));
        EXPECT_EQ(d2, e2);
        EXPECT_NEAR(d2, truth.front(), 1e-12);  // the tree works in a local frame: rounding only
      }
      differing += d2 > truth.front() + 1e-12;
      IndexList idx;
      std::vector<double> kd2;
      tree.knn(x, 8, idx, kd2);
      ASSERT_EQ(kd2.size(), 8u);
      for (std::size_t j = 0; j < kd2.size(); ++j)
        EXPECT_LE(kd2[j], (1.0 + eps) * truth[j] * (1.0 + 1e-12) + 1e-15) << "eps " << eps << " slot " << j;
    }
    if (eps == 0.0) {
      EXPECT_EQ(differing, 0);
    }
  }
  KdTreeParams bad;
  bad.eps = -0.1;
  try {
    KdTree t(pts, bad);
    FAIL() << "negative eps accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "eps");
  }
}

// Clouds at 1e6 from the origin with extents 1e-4 .. 1e4: batch kNN in random query order against brute
// force on the exact local offsets. The tree stores doubles relative to its centroid, so the only error is
// rounding the world coordinates: |coordinate error| <= delta = 1e6 x 2^-52 per axis, hence
// |d2 error| <= 2 sqrt(3) delta d + 3 delta^2 (a float32 store would miss by ~0.06 here).
TEST(KdTree, BatchKnnExactAtMillionOffsets) {
  const Vec3 far(1e6, -1e6, 1e6);
  const double delta = 1e6 * std::ldexp(1.0, -52);
  for (double scale : {1e-4, 1.0, 1e4}) {
    const Points local = random_cloud(4000, 71, scale);
    const Points qlocal = random_cloud(400, 72, 1.1 * scale);
    Points pts = local, queries = qlocal;
    pts.rowwise() += far.transpose();
    queries.rowwise() += far.transpose();
    KdTreeParams p;
    p.threads = 2;
    const KdTree tree(pts, p);
    for (int k : {1, 10}) {
      const KnnResult r = tree.knn(queries, k);
      for (Eigen::Index q = 0; q < queries.rows(); ++q) {
        const std::vector<double> truth = brute_dist2(local, qlocal.row(q).transpose());
        for (int j = 0; j < k; ++j) {
          const double tol = 2.0 * std::sqrt(3.0) * delta * std::sqrt(truth[j]) + 3.0 * delta * delta;
          EXPECT_NEAR(r.dist2(q, j), truth[j], tol) << "scale " << scale << " k " << k << " rank " << j;
          const Index row = r.indices(q, j);
          ASSERT_GE(row, 0);
          EXPECT_NEAR((local.row(row) - qlocal.row(q)).squaredNorm(), truth[j], tol);
        }
      }
    }
  }
}

// Exact ties everywhere (integer grid, queries on grid points and cell centres): batches in any query order
// and thread count return the same rows as single queries (the smaller-slot tie rule), ascending, and the
// distances of brute force.
TEST(KdTree, TiesGiveTheSameRowsInAnyOrderAndThreadCount) {
  // 41^3 = 68,921 points: above the size from which batches are answered along the Morton curve.
  constexpr int m = 41;
  Points grid(m * m * m, 3);
  for (int i = 0; i < m * m * m; ++i) grid.row(i) << i % m, (i / m) % m, i / (m * m);
  std::mt19937_64 rng(81);
  std::uniform_int_distribution<int> cell(0, m - 2);
  Points queries(600, 3);
  for (int i = 0; i < 600; ++i) {
    const double half = i % 2 ? 0.5 : 0.0;
    queries.row(i) << cell(rng) + half, cell(rng) + half, cell(rng) + half;
  }
  for (int k : {1, 6}) {
    KdTreeParams one;
    one.threads = 1;
    one.leaf_size = 3;
    const KnnResult ref = KdTree(grid, one).knn(queries, k);
    for (int threads : {1, 2, 3}) {
      KdTreeParams p = one;
      p.threads = threads;
      const KdTree tree(grid, p);
      const KnnResult r = tree.knn(queries, k);
      EXPECT_EQ(r.indices, ref.indices) << "threads " << threads;
      // Reversed query order: row q of the answer belongs to query q.
      const Points reversed = queries.colwise().reverse();
      const KnnResult rr = tree.knn(reversed, k);
      EXPECT_EQ(Eigen::MatrixXi(rr.indices.colwise().reverse()), Eigen::MatrixXi(ref.indices));
      for (Eigen::Index q = 0; q < queries.rows(); q += 37) {
        IndexList idx;
        std::vector<double> d2;
        tree.knn(queries.row(q).transpose(), k, idx, d2);
        for (int j = 0; j < k; ++j) EXPECT_EQ(idx[j], ref.indices(q, j));
        expect_knn_matches(grid, queries.row(q).transpose(), k, idx, d2);
      }
    }
  }
}

// Repeated queries on a line (cells as thin as their points): the warm start from the previous query's
// answer bounds the search by exactly the k-th distance, which must still be found (a cell bound that
// rounds an ulp above a point's distance would prune it; scipy's collinear case in Python caught that).
TEST(KdTree, WarmStartFromAnIdenticalQueryKeepsTheKthNeighbour) {
  Points line = Points::Zero(200, 3);
  line.col(0) = random_cloud(200, 83).col(0);
  Points queries = random_cloud(150, 84, 1.0);
  queries.col(1) *= 1e-9;
  queries.col(2) *= 1e-9;
  Points twice(300, 3);
  for (int i = 0; i < 150; ++i) twice.row(2 * i) = twice.row(2 * i + 1) = queries.row(i);
  for (int leaf : {1, 10, 50}) {
    const KnnResult r = KdTree(line, KdTreeParams{leaf, 1}).knn(twice, 8);
    for (Eigen::Index q = 0; q < twice.rows(); ++q) {
      const IndexList idx(r.indices.row(q).data(), r.indices.row(q).data() + 8);
      const std::vector<double> d2(r.dist2.row(q).data(), r.dist2.row(q).data() + 8);
      expect_knn_matches(line, twice.row(q).transpose(), 8, idx, d2);
    }
  }
}

// nearest_within: with a bound from any point of the cloud the answer equals nearest(); a bound below the
// true distance gives -1; a bad bound is refused.
TEST(KdTree, NearestWithinWarmStart) {
  const Points pts = random_cloud(3000, 95);
  const Points queries = random_cloud(300, 96, 1.3);
  const KdTree tree(pts);
  std::mt19937_64 rng(97);
  std::uniform_int_distribution<int> any(0, 2999);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Vec3 x = queries.row(q).transpose();
    const double best = brute_dist2(pts, x).front();
    double d_cold = 0.0, d_warm = 0.0, d_none = 0.0;
    const Index cold = tree.nearest(x, &d_cold);
    const double bound = (pts.row(any(rng)).transpose() - x).squaredNorm();
    EXPECT_EQ(tree.nearest_within(x, bound, &d_warm), cold);
    EXPECT_EQ(d_warm, d_cold);
    EXPECT_NEAR(d_cold, best, 1e-12);
    EXPECT_EQ(tree.nearest_within(x, 0.5 * best, &d_none), -1);
    EXPECT_TRUE(std::isinf(d_none));
  }
  for (double bad : {-1.0, std::nan("")}) {
    try {
      tree.nearest_within(Vec3::Zero(), bad);
      FAIL() << "bad bound accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "max_dist2");
    }
  }
}

}  // namespace
}  // namespace surfeledit
