// The k-d tree's leaf scans (KdScan: scalar, AVX2, AVX-512VL): every scan available on this CPU gives the scalar scan's
// rows and squared distances bit for bit (ties, 1e6 offsets, tiny and huge scales, leaves of one point, the
// masked lanes past a leaf's end), and the scalar scan agrees with brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "random_data.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

std::vector<KdScan> vector_scans() {
  std::vector<KdScan> out;
  for (KdScan s : {KdScan::Avx2, KdScan::Avx512})
    if (kd_scan_available(s)) out.push_back(s);
  return out;
}


// Points on an integer lattice (spacing `h`): queries at cell centres and lattice points meet many ties.
Points lattice(int side, double h, const Vec3& offset) {
  Points p(side * side * side, 3);
  int r = 0;
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      for (int k = 0; k < side; ++k) p.row(r++) = (offset + h * Vec3(i, j, k)).transpose();
  return p;
}

KdTree make(const Points& pts, int leaf, KdScan scan) {
  KdTreeParams p;
  p.leaf_size = leaf;
  p.threads = 1;
  p.scan = scan;
  return KdTree(pts, p);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every query kind of `tree` against the scalar tree over the same points: identical rows, identical bits.
void expect_same_as_scalar(const Points& pts, const Points& queries, int leaf, KdScan scan, double radius) {
  const KdTree ref = make(pts, leaf, KdScan::Scalar);
  const KdTree tree = make(pts, leaf, scan);
  for (Eigen::Index i = 0; i < queries.rows(); ++i) {
    const Vec3 q = queries.row(i).transpose();
    double da = 0.0, db = 0.0;
    ASSERT_EQ(tree.nearest(q, &da), ref.nearest(q, &db)) << "query " << i;
    ASSERT_TRUE(same_bits(da, db)) << da << " vs " << db;
    for (int k : {1, 3, 10}) {
      IndexList ia, ib;
      std::vector<double> ea, eb;
      tree.knn(q, k, ia, ea);
      ref.knn(q, k, ib, eb);
      ASSERT_EQ(ia, ib) << "query " << i << " k " << k;
      for (std::size_t j = 0; j < ea.size(); ++j) ASSERT_TRUE(same_bits(ea[j], eb[j]));
    }
    IndexList ia, ib;
    std::vector<double> ea, eb;
    tree.radius(q, radius, ia, ea);
    ref.radius(q, radius, ib, eb);
    ASSERT_EQ(ia, ib) << "query " << i;
    for (std::size_t j = 0; j < ea.size(); ++j) ASSERT_TRUE(same_bits(ea[j], eb[j]));
  }
  for (int k : {1, 4}) {
    const KnnResult a = tree.knn(queries, k), b = ref.knn(queries, k);
    ASSERT_EQ(a.indices, b.indices);
    ASSERT_EQ(std::memcmp(a.dist2.data(), b.dist2.data(), sizeof(double) * a.dist2.size()), 0);
  }
}

TEST(KdTreeScan, ScalarAndAutoAreAlwaysAvailable) {
  EXPECT_TRUE(kd_scan_available(KdScan::Auto));
  EXPECT_TRUE(kd_scan_available(KdScan::Scalar));
  // The AVX2 scan needs the CPU's AVX2 (and a build for x86-64).
  if (!__builtin_cpu_supports("avx2")) EXPECT_FALSE(kd_scan_available(KdScan::Avx2));
  // Its AVX-512VL build needs AVX-512F, VL and DQ.
  if (!__builtin_cpu_supports("avx512f") || !__builtin_cpu_supports("avx512vl") || !__builtin_cpu_supports("avx512dq"))
    EXPECT_FALSE(kd_scan_available(KdScan::Avx512));
  // A scan that does not exist is refused with a typed error naming the field.
  KdTreeParams p;
  p.scan = static_cast<KdScan>(9);
  EXPECT_FALSE(kd_scan_available(p.scan));
  try {
    KdTree(Points::Zero(4, 3), p);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), "scan");
  }
}

TEST(KdTreeScan, VectorScansEqualScalarOnRandomCloudsOffsetsAndScales) {
  for (KdScan scan : vector_scans()) {
    int seed = 1;
    for (double scale : {1e-4, 1.0, 1e4}) {
      for (const Vec3& off : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
        const Points pts = test::uniform_cloud(700, seed, scale, off);
        const Points queries = test::uniform_cloud(60, seed + 100, 1.3 * scale, off);
        for (int leaf : {1, 3, 4, 5, 8, 10, 24, 33}) expect_same_as_scalar(pts, queries, leaf, scan, 0.3 * scale);
        ++seed;
      }
    }
  }
}

// Lattice queries at lattice points, cell centres and edge midpoints: up to eight equidistant points, so the
// winner is decided by the tie rule alone. Leaves of 13 and 48 points take the k = 1 scan's two accumulators
// (blocks of eight, merged lane by lane) and its whole and partial last vectors, with ties across all of them.
TEST(KdTreeScan, VectorScansBreakTiesAsScalar) {
  for (KdScan scan : vector_scans()) {
    for (const Vec3& off : {Vec3(0, 0, 0), Vec3(1e6, 1e6, -1e6)}) {
      const Points pts = lattice(9, 0.5, off);
      Points queries(3 * 64, 3);
      for (int i = 0; i < 64; ++i) {
        const Vec3 base = off + 0.5 * Vec3(1 + i % 4, 1 + (i / 4) % 4, 1 + i / 16);
        queries.row(3 * i) = base.transpose();
        queries.row(3 * i + 1) = (base + Vec3(0.25, 0.25, 0.25)).transpose();
        queries.row(3 * i + 2) = (base + Vec3(0.25, 0.0, 0.0)).transpose();
      }
      for (int leaf : {1, 2, 7, 13, 16, 24, 48}) expect_same_as_scalar(pts, queries, leaf, scan, 0.5);
    }
  }
}

// The lanes past a leaf's last point read the next leaf or the tree's zero tail; the tail is the local origin
// (the centroid), so a query there would win with distance 0 if those lanes counted. No point lies near the
// centroid of two far clusters: the answer must be a real point, the brute-force nearest.
TEST(KdTreeScan, LanesPastALeafNeverWin) {
  for (KdScan scan : vector_scans()) {
    for (int n = 2; n <= 19; ++n) {  // (one point is its own centroid)
      Points pts(n, 3);
      for (int i = 0; i < n; ++i) pts.row(i) = Vec3(i % 2 ? 10.0 + 0.1 * i : -10.0 - 0.1 * i, 0.01 * i, 0.0).transpose();
      const Vec3 centroid = pts.colwise().mean().transpose();
      for (int leaf : {1, 2, 3, 5, 8, 32}) {
        const KdTree tree = make(pts, leaf, scan);
        double d2 = 0.0;
        const Index j = tree.nearest(centroid, &d2);
        ASSERT_GE(j, 0);
        ASSERT_LT(j, n);
        double best = std::numeric_limits<double>::infinity();
        for (int i = 0; i < n; ++i) best = std::min(best, (pts.row(i).transpose() - centroid).squaredNorm());
        EXPECT_NEAR(d2, best, 1e-9 * best) << "n " << n << " leaf " << leaf;
        EXPECT_GT(d2, 1.0);
        IndexList idx;
        std::vector<double> dd;
        tree.knn(centroid, n + 3, idx, dd);
        ASSERT_EQ(static_cast<int>(idx.size()), n);
        for (Index r : idx) {
          ASSERT_GE(r, 0);
          ASSERT_LT(r, n);
        }
        tree.radius(centroid, 1e9, idx, dd);
        ASSERT_EQ(static_cast<int>(idx.size()), n);
      }
      const Points queries = test::uniform_cloud(20, 7 + n, 12.0, Vec3::Zero());
      expect_same_as_scalar(pts, queries, 4, scan, 5.0);
    }
  }
}

// Coordinates near 1e200: every squared distance overflows to +inf; the scalar scan then offers a leaf's first
// point and every scan must return the same row.
TEST(KdTreeScan, OverflowingDistancesGiveTheScalarRow) {
  for (KdScan scan : vector_scans()) {
    const Points pts = test::uniform_cloud(50, 3, 1e200, Vec3::Zero());
    const Points queries = test::uniform_cloud(10, 4, 1e200, Vec3::Zero());
    for (int leaf : {1, 6, 24}) expect_same_as_scalar(pts, queries, leaf, scan, 1e150);
  }
}

// The scalar scan (and so every scan) against brute force: the nearest distance is the true minimum, and
// duplicates of one point all tie (any of them may win, the same one in every scan).
TEST(KdTreeScan, ScalarScanMatchesBruteForce) {
  const Points pts = test::uniform_cloud(2000, 11, 1.0, Vec3(1e6, 2e6, -3e6));
  const Points queries = test::uniform_cloud(200, 12, 1.1, Vec3(1e6, 2e6, -3e6));
  for (int leaf : {1, 10, 24}) {
    const KdTree tree = make(pts, leaf, KdScan::Scalar);
    for (Eigen::Index i = 0; i < queries.rows(); ++i) {
      const Vec3 q = queries.row(i).transpose();
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index r = 0; r < pts.rows(); ++r) best = std::min(best, (pts.row(r).transpose() - q).squaredNorm());
      double d2 = 0.0;
      const Index j = tree.nearest(q, &d2);
      EXPECT_NEAR((pts.row(j).transpose() - q).squaredNorm(), best, 1e-9 * (1.0 + best));
      EXPECT_NEAR(d2, best, 1e-9 * (1.0 + best));
    }
  }
  for (KdScan scan : vector_scans()) expect_same_as_scalar(pts, queries, 24, scan, 0.2);
}

TEST(KdTreeScan, EmptyAndSinglePointTrees) {
  for (KdScan scan : vector_scans()) {
    const Points none(0, 3);
    const KdTree empty = make(none, 10, scan);
    EXPECT_EQ(empty.nearest(Vec3(1, 2, 3)), -1);
    Points one(1, 3);
    one << 1e6, -1e6, 5.0;
    const KdTree single = make(one, 10, scan);
    double d2 = -1.0;
    EXPECT_EQ(single.nearest(Vec3(0, 0, 0), &d2), 0);
    EXPECT_GT(d2, 0.0);
    expect_same_as_scalar(one, test::uniform_cloud(5, 9, 3.0, Vec3(1e6, -1e6, 5.0)), 1, scan, 2.0);
  }
}

}  // namespace
}  // namespace surfeledit
