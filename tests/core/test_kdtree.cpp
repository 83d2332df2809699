// k-d tree kNN and radius queries against brute force on random and degenerate point sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

Points random_cloud(int n, std::uint64_t seed, double scale = 1.0, const Vec3& offset = Vec3::Zero()) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points p(n, 3);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) p(i, d) = offset[d] + scale * u(rng);
  }
  return p;
}

// Squared distances (model units^2) from q to every row of `points` listed in `rows` (all rows when empty).
std::vector<double> brute_dist2(const Points& points, const Vec3& q, const IndexList& rows = {}) {
  std::vector<double> d;
  if (rows.empty()) {
    for (Eigen::Index i = 0; i < points.rows(); ++i) d.push_back((points.row(i).transpose() - q).squaredNorm());
  } else {
    for (Index i : rows) d.push_back((points.row(i).transpose() - q).squaredNorm());
  }
  std::sort(d.begin(), d.end());
  return d;
}

// Checks a kNN answer: ascending, the distances equal the k smallest brute-force ones (as a multiset,
// so ties may pick any index), and every returned dist2 is the true distance of the returned row.
void expect_knn_matches(const Points& points, const Vec3& q, int k, const IndexList& idx,
                        const std::vector<double>& d2, const IndexList& rows = {}) {
  const std::vector<double> truth = brute_dist2(points, q, rows);
  const std::size_t expect = std::min<std::size_t>(static_cast<std::size_t>(k), truth.size());
  ASSERT_EQ(idx.size(), expect);
  ASSERT_EQ(d2.size(), expect);
  for (std::size_t j = 0; j < expect; ++j) {
    const double tol = 1e-12 * (1.0 + truth[j]);
    EXPECT_NEAR(d2[j], truth[j], tol) << "rank " << j;
    ASSERT_GE(idx[j], 0);
    ASSERT_LT(idx[j], points.rows());
    EXPECT_NEAR((points.row(idx[j]).transpose() - q).squaredNorm(), d2[j], tol);
    if (j > 0) {
      EXPECT_LE(d2[j - 1], d2[j]);
    }
    if (!rows.empty()) {
      EXPECT_NE(std::find(rows.begin(), rows.end(), idx[j]), rows.end());
    }
  }
  // no duplicate rows
  IndexList sorted = idx;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
}

void expect_radius_matches(const Points& points, const Vec3& q, double r, const IndexList& idx,
                           const std::vector<double>& d2, const IndexList& rows = {}) {
  std::vector<double> truth;
  for (double d : brute_dist2(points, q, rows)) {
    if (d <= r * r) truth.push_back(d);
  }
  ASSERT_EQ(idx.size(), truth.size()) << "radius " << r;
  for (std::size_t j = 0; j < truth.size(); ++j) {
    EXPECT_NEAR(d2[j], truth[j], 1e-12 * (1.0 + truth[j]));
    EXPECT_NEAR((points.row(idx[j]).transpose() - q).squaredNorm(), d2[j], 1e-12 * (1.0 + truth[j]));
    if (j > 0) {
      EXPECT_LE(d2[j - 1], d2[j]);
    }
  }
}

TEST(KdTree, KnnMatchesBruteForceOnRandomClouds) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const Points pts = random_cloud(2000, seed);
    const KdTree tree(pts);
    EXPECT_EQ(tree.size(), 2000);
    const Points queries = random_cloud(100, seed + 100, 1.3);
    for (int k : {1, 5, 17}) {
      for (Eigen::Index q = 0; q < queries.rows(); ++q) {
        IndexList idx;
        std::vector<double> d2;
        tree.knn(queries.row(q).transpose(), k, idx, d2);
        expect_knn_matches(pts, queries.row(q).transpose(), k, idx, d2);
      }
    }
  }
}

TEST(KdTree, NearestMatchesBruteForceAndSelfQueryIsZero) {
  const Points pts = random_cloud(1500, 7);
  const KdTree tree(pts);
  for (Eigen::Index i = 0; i < 200; ++i) {
    double d2 = -1.0;
    const Index j = tree.nearest(pts.row(i).transpose(), &d2);
    EXPECT_EQ(j, i);
    EXPECT_EQ(d2, 0.0);
  }
  const Points queries = random_cloud(300, 8, 2.0);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    double d2 = -1.0;
    const Index j = tree.nearest(queries.row(q).transpose(), &d2);
    EXPECT_NEAR(d2, brute_dist2(pts, queries.row(q).transpose()).front(), 1e-12);
    EXPECT_NEAR((pts.row(j) - queries.row(q)).squaredNorm(), d2, 1e-12);
  }
}

TEST(KdTree, RadiusMatchesBruteForceAndIsInclusive) {
  const Points pts = random_cloud(3000, 11);
  const KdTree tree(pts);
  const Points queries = random_cloud(60, 12, 1.2);
  for (double r : {0.0, 0.05, 0.2, 0.6, 5.0}) {
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      IndexList idx;
      std::vector<double> d2;
      tree.radius(queries.row(q).transpose(), r, idx, d2);
      expect_radius_matches(pts, queries.row(q).transpose(), r, idx, d2);
    }
  }
  // Inclusive: a point at exactly the radius is returned (axis-aligned so the distance is exact).
  Points line(3, 3);
  line << 0, 0, 0, 0.5, 0, 0, 1.0, 0, 0;
  const KdTree lt(line);
  IndexList idx;
  std::vector<double> d2;
  lt.radius(Vec3::Zero(), 0.5, idx, d2);
  ASSERT_EQ(idx.size(), 2u);
  EXPECT_EQ(idx[1], 1);
  EXPECT_EQ(d2[1], 0.25);
}

TEST(KdTree, DuplicatePointsAreAllReturned) {
  Points pts(50, 3);
  for (int i = 0; i < 50; ++i) pts.row(i) = (i < 30 ? Vec3(0.1, 0.2, 0.3) : Vec3(0.1 * i, 0, 0)).transpose();
  const KdTree tree(pts, KdTreeParams{4, 1});
  IndexList idx;
  std::vector<double> d2;
  tree.knn(Vec3(0.1, 0.2, 0.3), 30, idx, d2);
  expect_knn_matches(pts, Vec3(0.1, 0.2, 0.3), 30, idx, d2);
  for (Index i : idx) EXPECT_LT(i, 30);  // the 30 duplicates are strictly nearest
  tree.radius(Vec3(0.1, 0.2, 0.3), 0.0, idx, d2);
  EXPECT_EQ(idx.size(), 30u);
  tree.knn(Vec3(0.1, 0.2, 0.31), 35, idx, d2);
  expect_knn_matches(pts, Vec3(0.1, 0.2, 0.31), 35, idx, d2);
}

TEST(KdTree, CoplanarAndCollinearSets) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points plane(800, 3), line(400, 3);
  for (int i = 0; i < 800; ++i) plane.row(i) << u(rng), u(rng), 0.25;
  for (int i = 0; i < 400; ++i) {
    const double t = u(rng);
    line.row(i) << t, 2 * t, -t;
  }
  for (const Points* pts : {&plane, &line}) {
    const KdTree tree(*pts, KdTreeParams{3, 0});
    for (int q = 0; q < 50; ++q) {
      const Vec3 query(u(rng), u(rng), u(rng));
      IndexList idx;
      std::vector<double> d2;
      tree.knn(query, 8, idx, d2);
      expect_knn_matches(*pts, query, 8, idx, d2);
      tree.radius(query, 0.4, idx, d2);
      expect_radius_matches(*pts, query, 0.4, idx, d2);
    }
  }
}

TEST(KdTree, SinglePointEmptyTreeAndLargeK) {
  Points one(1, 3);
  one << 1, 2, 3;
  const KdTree t1(one);
  double d2 = 0;
  EXPECT_EQ(t1.nearest(Vec3(1, 2, 4), &d2), 0);
  EXPECT_DOUBLE_EQ(d2, 1.0);
  IndexList idx;
  std::vector<double> dd;
  t1.knn(Vec3::Zero(), 10, idx, dd);  // k larger than the point count
  ASSERT_EQ(idx.size(), 1u);
  EXPECT_EQ(idx[0], 0);

  const Points pts = random_cloud(7, 3);
  const KdTree t7(pts);
  t7.knn(Vec3::Zero(), 100, idx, dd);
  expect_knn_matches(pts, Vec3::Zero(), 100, idx, dd);
  const KnnResult batch = t7.knn(random_cloud(4, 9), 10);
  ASSERT_EQ(batch.indices.rows(), 4);
  ASSERT_EQ(batch.indices.cols(), 10);
  for (int q = 0; q < 4; ++q) {
    for (int j = 7; j < 10; ++j) {
      EXPECT_EQ(batch.indices(q, j), -1);
      EXPECT_TRUE(std::isinf(batch.dist2(q, j)));
    }
    for (int j = 0; j < 7; ++j) EXPECT_GE(batch.indices(q, j), 0);
  }

  const KdTree empty{Points(0, 3)};
  EXPECT_EQ(empty.size(), 0);
  EXPECT_EQ(empty.nearest(Vec3::Zero(), &d2), -1);
  EXPECT_TRUE(std::isinf(d2));
  empty.knn(Vec3::Zero(), 3, idx, dd);
  EXPECT_TRUE(idx.empty());
  empty.radius(Vec3::Zero(), 1.0, idx, dd);
  EXPECT_TRUE(idx.empty());
}

TEST(KdTree, EmptyQuerySet) {
  const KdTree tree(random_cloud(100, 1));
  const KnnResult k = tree.knn(Points(0, 3), 5);
  EXPECT_EQ(k.indices.rows(), 0);
  const RadiusResult r = tree.radius(Points(0, 3), 0.3);
  ASSERT_EQ(r.offsets.size(), 1u);
  EXPECT_EQ(r.offsets[0], 0);
  EXPECT_TRUE(r.indices.empty());
}

TEST(KdTree, SubsetTreeReturnsFullArrayRows) {
  const Points pts = random_cloud(1000, 21);
  IndexList subset;
  for (Index i = 0; i < 1000; i += 3) subset.push_back(i);
  const KdTree tree(pts, subset);
  EXPECT_EQ(tree.size(), static_cast<Index>(subset.size()));
  const Points queries = random_cloud(80, 22);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Vec3 x = queries.row(q).transpose();
    IndexList idx;
    std::vector<double> d2;
    tree.knn(x, 6, idx, d2);
    expect_knn_matches(pts, x, 6, idx, d2, subset);
    for (Index i : idx) EXPECT_EQ(i % 3, 0);
    tree.radius(x, 0.3, idx, d2);
    expect_radius_matches(pts, x, 0.3, idx, d2, subset);
    for (Index i : idx) EXPECT_EQ(i % 3, 0);
  }
  EXPECT_THROW(KdTree(pts, IndexList{0, 1000}), Error);
  EXPECT_THROW(KdTree(pts, IndexList{-1}), Error);
}

TEST(KdTree, BatchEqualsSingleAcrossThreadCounts) {
  const Points pts = random_cloud(5000, 31);
  const Points queries = random_cloud(700, 32, 1.1);
  for (int threads : {0, 1, 2}) {
    const KdTree tree(pts, KdTreeParams{10, threads});
    const KnnResult batch = tree.knn(queries, 4);
    const RadiusResult rb = tree.radius(queries, 0.15);
    ASSERT_EQ(rb.offsets.size(), static_cast<std::size_t>(queries.rows()) + 1);
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      IndexList idx;
      std::vector<double> d2;
      tree.knn(queries.row(q).transpose(), 4, idx, d2);
      for (int j = 0; j < 4; ++j) {
        EXPECT_EQ(batch.indices(q, j), idx[j]);
        EXPECT_EQ(batch.dist2(q, j), d2[j]);
      }
      tree.radius(queries.row(q).transpose(), 0.15, idx, d2);
      ASSERT_EQ(static_cast<std::size_t>(rb.offsets[q + 1] - rb.offsets[q]), idx.size());
      for (std::size_t j = 0; j < idx.size(); ++j) {
        EXPECT_EQ(rb.indices[rb.offsets[q] + j], idx[j]);
        EXPECT_EQ(rb.dist2[rb.offsets[q] + j], d2[j]);
      }
    }
  }
}

TEST(KdTree, AllLeafSizesAgreeWithBruteForce) {
  const Points pts = random_cloud(600, 41);
  const Points queries = random_cloud(40, 42);
  for (int leaf = 1; leaf <= 50; ++leaf) {
    const KdTree tree(pts, KdTreeParams{leaf, 1});
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      IndexList idx;
      std::vector<double> d2;
      tree.knn(queries.row(q).transpose(), 3, idx, d2);
      expect_knn_matches(pts, queries.row(q).transpose(), 3, idx, d2);
      tree.radius(queries.row(q).transpose(), 0.25, idx, d2);
      expect_radius_matches(pts, queries.row(q).transpose(), 0.25, idx, d2);
    }
  }
}

TEST(KdTree, PrecisionFarFromTheOrigin) {
  // A cloud of extent 1e-3 at 1e7 from the origin: neighbours are still exact (the tree works
  // relative to the centroid); brute force on the offsets relative to the same anchor is the truth.
  const Vec3 far(1e7, -2e7, 3e7);
  const Points local = random_cloud(500, 51, 1e-3);
  Points pts = local;
  pts.rowwise() += far.transpose();
  const KdTree tree(pts);
  const Points qlocal = random_cloud(50, 52, 1e-3);
  for (Eigen::Index q = 0; q < qlocal.rows(); ++q) {
    const Vec3 x = qlocal.row(q).transpose() + far;
    const Index j = tree.nearest(x);
    const Vec3 xl = x - far;  // exact-enough local query
    const double best = brute_dist2(pts.rowwise() - far.transpose(), xl).front();
    EXPECT_NEAR((pts.row(j).transpose() - far - xl).squaredNorm(), best, 1e-14);
  }
}

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
    if (eps == 0.0) EXPECT_EQ(differing, 0);
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

// Exponentially spaced points (each 2x closer to the origin than the last) defeat midpoint cuts; the tree
// must still be exact and shallow enough to search (no deep recursion).
TEST(KdTree, ExponentiallySpacedPoints) {
  Points pts(900, 3);
  for (int i = 0; i < 900; ++i) pts.row(i) << std::ldexp(1.0, -i), std::ldexp(1.0, -(i % 300)), 0.5 * (i % 2);
  const KdTree tree(pts, KdTreeParams{2, 1});
  const Points queries = random_cloud(100, 98, 0.6);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    IndexList idx;
    std::vector<double> d2;
    tree.knn(queries.row(q).transpose(), 5, idx, d2);
    expect_knn_matches(pts, queries.row(q).transpose(), 5, idx, d2);
  }
}

TEST(KdTree, RejectsBadInput) {
  Points pts = random_cloud(10, 1);
  EXPECT_THROW(KdTree(pts, KdTreeParams{0, 0}), Error);
  EXPECT_THROW(KdTree(pts, KdTreeParams{10, -1}), Error);
  pts(3, 1) = std::numeric_limits<double>::quiet_NaN();
  try {
    KdTree t(pts);
    FAIL() << "non-finite input accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), "points");
  }
  const KdTree ok(random_cloud(10, 2));
  IndexList idx;
  std::vector<double> d2;
  EXPECT_THROW(ok.radius(Vec3::Zero(), -1.0, idx, d2), Error);
  EXPECT_THROW(ok.knn(Vec3::Zero(), -1, idx, d2), Error);
  EXPECT_THROW(ok.nearest(Vec3(std::nan(""), 0, 0)), Error);
  try {
    ok.knn(Points::Zero(1000, 3), 1 << 20);  // 2^30 padded entries
    FAIL() << "huge k accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::TooLarge);
  }
  Points bad_q = Points::Zero(3, 3);
  bad_q(1, 1) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ok.knn(bad_q, 2), Error);
  EXPECT_THROW(ok.radius(bad_q, 0.1), Error);
}

TEST(KdTree, MoveAndMemory) {
  const Points pts = random_cloud(1000, 61);
  KdTree a(pts);
  const std::size_t bytes = a.memory_bytes();
  EXPECT_GE(bytes, 1000 * 3 * sizeof(double));
  KdTree b(std::move(a));
  EXPECT_EQ(b.size(), 1000);
  EXPECT_EQ(b.nearest(pts.row(17).transpose()), 17);
}

}  // namespace
}  // namespace surfeledit
