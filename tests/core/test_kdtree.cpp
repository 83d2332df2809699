// k-d tree kNN and radius queries against brute force on random and degenerate point sets; bad input, moves.
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
