// KdTree::nearest_from (the search that starts at a leaf and walks up) against brute force and against the
// root descent, bit for bit: random clouds, exact ties (duplicates, lattices, queries equidistant from 2-8
// points), every possible start value (each node of the tree, non-leaf nodes and out-of-range values, which
// start from the near-path leaf, a leaf of another tree), 1e6 offsets, 1e+-4 scales, and cuts whose float
// bounds overlap; each with the baseline walk (KdScan::Scalar, one level at a time) and each vector one the CPU has
// (AVX2 and its AVX-512VL build, by fans of three levels), which must also agree with each other on the winner's leaf.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "random_data.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

KdTreeParams with_cells(int leaf_size, KdScan scan = KdScan::Auto) {
  KdTreeParams p;
  p.leaf_size = leaf_size;
  p.cells = true;
  p.threads = 1;
  p.scan = scan;
  return p;
}

// The baseline leaf scan and walk, and each vector one this CPU has (AVX2, its AVX-512VL build).
const std::vector<KdScan> kScans = [] {
  std::vector<KdScan> out{KdScan::Scalar};
  for (KdScan s : {KdScan::Avx2, KdScan::Avx512})
    if (kd_scan_available(s)) out.push_back(s);
  return out;
}();

// The rows at the smallest squared distance from q (brute force over every row; `offset` is subtracted from
// both sides first, as the tree works relative to its points' centroid, so far from the origin the comparison
// is between the same small differences).
IndexList nearest_rows(const Points& pts, const Vec3& q, const Vec3& offset, double* best_out) {
  double best = std::numeric_limits<double>::infinity();
  IndexList rows;
  const Vec3 ql = q - offset;
  for (Eigen::Index i = 0; i < pts.rows(); ++i) {
    const double d2 = (pts.row(i).transpose() - offset - ql).squaredNorm();
    if (d2 < best) {
      best = d2;
      rows.assign(1, static_cast<Index>(i));
    } else if (d2 == best) {
      rows.push_back(static_cast<Index>(i));
    }
  }
  *best_out = best;
  return rows;
}

// One query from one start value: the row and the dist2 bits of the root descent (nearest), a row among the
// brute-force nearest ones (within `tol` of its distance, for rounding of the tree's local frame), and a leaf
// out that, passed again, gives the same answer.
void expect_same_as_root(const KdTree& tree, const Points& pts, const Vec3& q, std::uint32_t start,
                         const Vec3& offset, double tol) {
  double d_root = 0.0, d_from = 0.0, d_again = 0.0;
  const Index root = tree.nearest(q, &d_root);
  std::uint32_t leaf = start;
  const Index from = tree.nearest_from(q, leaf, &d_from);
  ASSERT_EQ(from, root) << "start " << start;
  ASSERT_EQ(d_from, d_root) << "start " << start;  // bit-identical
  double best = 0.0;
  const IndexList truth = nearest_rows(pts, q, offset, &best);
  EXPECT_NE(std::find(truth.begin(), truth.end(), from), truth.end()) << "start " << start;
  EXPECT_NEAR(d_from, best, tol * (1.0 + best));
  std::uint32_t again = leaf;
  EXPECT_EQ(tree.nearest_from(q, again, &d_again), root);
  EXPECT_EQ(again, leaf);  // the winner's leaf is a fixed point
  EXPECT_EQ(d_again, d_root);
}

// Start values worth trying on `tree`: every value up to a bound on its node count (so every leaf, every inner
// node, and some past the last node), 0, and the largest values.
std::vector<std::uint32_t> every_start(const KdTree& tree) {
  std::vector<std::uint32_t> s;
  const std::uint32_t bound = static_cast<std::uint32_t>(2 * tree.size() + 4);
  for (std::uint32_t v = 0; v < bound; ++v) s.push_back(v);
  s.push_back(std::numeric_limits<std::uint32_t>::max());
  s.push_back(0x80000000u);
  return s;
}

TEST(KdTreeFromLeaf, EveryStartGivesTheRootAnswerOnRandomClouds) {
  for (int leaf_size : {1, 4, 10, 48}) {
    for (KdScan scan : kScans) {
      const Points pts = test::uniform_cloud(300, 11 + leaf_size, 1.0, Vec3::Zero());
      const KdTree tree(pts, with_cells(leaf_size, scan));
      const Points queries = test::uniform_cloud(20, 12, 1.3, Vec3::Zero());
      for (Eigen::Index i = 0; i < queries.rows(); ++i)
        for (std::uint32_t s : every_start(tree))
          expect_same_as_root(tree, pts, queries.row(i).transpose(), s, Vec3::Zero(), 1e-12);
    }
  }
}

// Queries that move a little each call, each starting at the previous answer's leaf (the Robust detector's
// use), and starts left by a far query or by another tree (stale or wrong leaves).
TEST(KdTreeFromLeaf, WalkingQueriesAndStaleStarts) {
  const Points pts = test::uniform_cloud(5000, 21, 1.0, Vec3::Zero());
  const KdTree tree(pts, with_cells(48));
  const KdTree other(test::uniform_cloud(900, 22, 1.0, Vec3::Zero()), with_cells(4));
  std::mt19937_64 rng(23);
  std::normal_distribution<double> step(0.0, 0.02);
  Vec3 q(0.3, -0.2, 0.1);
  std::uint32_t leaf = 0, stale = 0;
  for (int i = 0; i < 400; ++i) {
    q += Vec3(step(rng), step(rng), step(rng));
    expect_same_as_root(tree, pts, q, leaf, Vec3::Zero(), 1e-12);
    tree.nearest_from(q, leaf);
    expect_same_as_root(tree, pts, -q, leaf, Vec3::Zero(), 1e-12);  // the start of a far query
    other.nearest_from(q, stale);
    expect_same_as_root(tree, pts, q, stale, Vec3::Zero(), 1e-12);  // another tree's leaf
  }
}

// Exact ties: every lattice point three times over, queried at lattice points (3 rows at distance 0), at
// half-integer offsets on 1, 2 or 3 axes (2, 4 or 8 points at equal distance, x3), and beyond the lattice.
TEST(KdTreeFromLeaf, TiesOnALatticeWithDuplicatesFromEveryStart) {
  constexpr int m = 7;
  Points pts(3 * m * m * m, 3);
  for (int i = 0; i < m * m * m; ++i)
    for (int c = 0; c < 3; ++c) pts.row(c * m * m * m + i) << i % m, (i / m) % m, i / (m * m);
  for (int leaf_size : {1, 3, 10}) {
    for (KdScan scan : kScans) {
      const KdTree tree(pts, with_cells(leaf_size, scan));
      std::mt19937_64 rng(31 + leaf_size);
      std::uniform_int_distribution<int> cell(0, m - 2), axes(0, 7);
      for (int i = 0; i < 24; ++i) {
        const int mask = axes(rng);
        Vec3 q(cell(rng), cell(rng), cell(rng));
        for (int d = 0; d < 3; ++d)
          if (mask & (1 << d)) q[d] += 0.5;
        if (i % 8 == 7) q[i % 3] = -2.5;  // outside the lattice, equidistant from a face's points
        for (std::uint32_t s : every_start(tree)) expect_same_as_root(tree, pts, q, s, Vec3::Zero(), 0.0);
      }
    }
  }
}

// The batch k = 1 query of a tree built with cells (KdTree::knn(queries, 1): along the Morton curve, each query
// warm-started from the previous answer, on one and two threads; the seeds of the detectors) gives each query the row
// and dist2 bits of its single search, on a lattice with every point three times (ties everywhere) and on a random
// cloud far from the origin.
TEST(KdTreeFromLeaf, BatchNearestIsTheSingleAnswer) {
  constexpr int m = 7;
  Points lattice(3 * m * m * m, 3);
  for (int i = 0; i < m * m * m; ++i)
    for (int c = 0; c < 3; ++c) lattice.row(c * m * m * m + i) << i % m, (i / m) % m, i / (m * m);
  const Points cloud = test::uniform_cloud(3000, 11, 1.0, Vec3(1e6, -1e6, 1e6));
  const Points* const sets[] = {&lattice, &cloud};
  for (const Points* pts : sets) {
    const Vec3 lo = pts->colwise().minCoeff().transpose(), hi = pts->colwise().maxCoeff().transpose();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-0.2, 1.2);
    Points queries(400, 3);
    for (Eigen::Index i = 0; i < queries.rows(); ++i) {
      Vec3 q;
      for (int d = 0; d < 3; ++d) q[d] = lo[d] + u(rng) * (hi[d] - lo[d]);
      if (pts == &lattice && i % 2 == 0) q = q.array().round() + 0.5 * Eigen::Array3d(i % 3 == 0, i % 5 == 0, 1.0);
      queries.row(i) = q.transpose();
    }
    for (int leaf_size : {1, 10, 96}) {
      for (KdScan scan : kScans) {
        KdTreeParams p = with_cells(leaf_size, scan);
        for (int threads : {1, 2}) {
          const KdTree tree(*pts, p);
          const KnnResult batch = tree.knn(queries, 1, threads);
          for (Eigen::Index i = 0; i < queries.rows(); ++i) {
            double d2 = 0.0;
            const Index row = tree.nearest(queries.row(i).transpose(), &d2);
            ASSERT_EQ(batch.indices(i, 0), row) << "query " << i << " leaf " << leaf_size << " threads " << threads;
            ASSERT_EQ(batch.dist2(i, 0), d2) << "query " << i;
          }
        }
      }
    }
  }
}

// Far from the origin and at tiny and huge scales: the local frame keeps the comparison exact enough, and the
// walk's stop (face gaps squared against the best dist2) must hold at every magnitude.
TEST(KdTreeFromLeaf, OffsetsAndScales) {
  for (const double scale : {1e-4, 1.0, 1e4}) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
      for (KdScan scan : kScans) {
        const Points pts = test::uniform_cloud(2000, 41, scale, offset);
        const KdTree tree(pts, with_cells(24, scan));
        const Points queries = test::uniform_cloud(60, 42, 1.2 * scale, offset);
        std::uint32_t leaf = 0;
        for (Eigen::Index i = 0; i < queries.rows(); ++i) {
          const Vec3 q = queries.row(i).transpose();
          for (std::uint32_t s : {leaf, 0u, 7u, 100u, ~0u}) expect_same_as_root(tree, pts, q, s, offset, 1e-9);
          tree.nearest_from(q, leaf);
        }
      }
    }
  }
}

// A cluster whose points lie closer together than a float's spacing at their coordinates: the median cuts
// between them get float bounds with lo > hi, whose cells must not stop the walk (kNoStop), and a point on
// the far side of such a cut must still be found from every start.
TEST(KdTreeFromLeaf, CutsInsideOneFloatInterval) {
  std::mt19937_64 rng(51);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Points pts(260, 3);
  for (int i = 0; i < 200; ++i) pts.row(i) << 1.0 + 1e-10 * i, 1.0 + 1e-10 * ((i * 7) % 200), 1.0;
  for (int i = 200; i < 260; ++i) pts.row(i) << -1.0 - u(rng), -1.0 - u(rng), u(rng) - 0.5;
  const Vec3 centroid = pts.colwise().mean().transpose();
  for (KdScan scan : kScans) {
    const KdTree tree(pts, with_cells(2, scan));
    for (int i = 0; i < 40; ++i) {
      const Vec3 q(1.0 + 1e-10 * (5 * i) + 3e-11, 1.0 + 1e-10 * ((i * 13) % 200), 1.0 + (i % 3) * 1e-9);
      for (std::uint32_t s : every_start(tree)) expect_same_as_root(tree, pts, q, s, centroid, 0.0);
    }
  }
}

// Median cuts through equal coordinates (lo == hi): a 5^3 lattice at spacing 2^-12, every point twice, inside
// one Morton cell of a box that 8 far corners make large; symmetric, so the tree's origin is 0 and every
// coordinate and distance is exact. A query half a step or a step off a lattice plane has tied nearest points
// on both sides of such a cut, the one of the smaller slot in the left child: a walk that stops at a right
// child whose face is exactly the best distance away (>= instead of >) returns the other one.
TEST(KdTreeFromLeaf, TiesAcrossCutsThroughEqualCoordinates) {
  constexpr double h = 1.0 / 4096.0;
  Points pts(2 * 125 + 8, 3);
  for (int i = 0; i < 125; ++i)
    for (int c = 0; c < 2; ++c) pts.row(2 * i + c) << (i % 5 - 2) * h, (i / 5 % 5 - 2) * h, (i / 25 - 2) * h;
  for (int i = 0; i < 8; ++i) pts.row(250 + i) << (i & 1 ? 1.0 : -1.0), (i & 2 ? 1.0 : -1.0), (i & 4 ? 1.0 : -1.0);
  for (int leaf_size : {1, 2, 3, 5}) {
    for (KdScan scan : kScans) {
      const KdTree tree(pts, with_cells(leaf_size, scan));
      for (int i = 0; i < 125; i += 3) {
        const Vec3 base((i % 5 - 2) * h, (i / 5 % 5 - 2) * h, (i / 25 - 2) * h);
        for (int axis = 0; axis < 3; ++axis) {
          for (const double off : {0.5 * h, -0.5 * h, 0.25 * h, 1.5 * h}) {
            Vec3 q = base;
            q[axis] += off;
            for (std::uint32_t s : every_start(tree)) expect_same_as_root(tree, pts, q, s, Vec3::Zero(), 0.0);
          }
        }
      }
    }
  }
}

// The baseline and the vector walk from the same start: the same row, dist2 bits and winner's leaf (their box
// tests decide alike), from every start (cold ones from the near-path leaf) at 1e6 offsets and 1e+-4 scales
// and on a lattice of exact ties.
TEST(KdTreeFromLeaf, ScalarAndVectorWalksAgree) {
  auto agree = [](const KdTree& a, const KdTree& b, const Vec3& q, std::uint32_t s) {
    std::uint32_t la = s, lb = s;
    double da = 0.0, db = 0.0;
    ASSERT_EQ(a.nearest_from(q, la, &da), b.nearest_from(q, lb, &db)) << "start " << s;
    ASSERT_EQ(da, db) << "start " << s;
    ASSERT_EQ(la, lb) << "start " << s;
  };
  for (const double scale : {1e-4, 1e4}) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
      const Points pts = test::uniform_cloud(1500, 71, scale, offset);
      const KdTree scalar(pts, with_cells(8, KdScan::Scalar));
      const Points queries = test::uniform_cloud(25, 72, 1.3 * scale, offset);
      for (KdScan scan : kScans) {
        const KdTree vector(pts, with_cells(8, scan));
        for (Eigen::Index i = 0; i < queries.rows(); ++i)
          for (std::uint32_t s : every_start(scalar)) agree(scalar, vector, queries.row(i).transpose(), s);
      }
    }
  }
  constexpr int m = 6;
  Points lattice(2 * m * m * m, 3);
  for (int i = 0; i < 2 * m * m * m; ++i) lattice.row(i) << i % m, (i / m) % m, (i / (m * m)) % m;
  const KdTree scalar(lattice, with_cells(3, KdScan::Scalar));
  for (KdScan scan : kScans) {
    const KdTree vector(lattice, with_cells(3, scan));
    for (int i = 0; i < 30; ++i) {
      const Vec3 q(0.5 * (i % 11), 0.5 * ((i * 7) % 11), 0.5 * ((i * 3) % 11) - 1.0);
      for (std::uint32_t s : every_start(scalar)) agree(scalar, vector, q, s);
    }
  }
}

// Without cells (or with eps > 0) nearest_from answers nearest(q) and leaves the start alone or sets a leaf.
TEST(KdTreeFromLeaf, TreesWithoutCellsAndScans) {
  const Points pts = test::uniform_cloud(800, 61, 1.0, Vec3::Zero());
  KdTreeParams plain;
  plain.threads = 1;
  const KdTree no_cells(pts, plain);
  KdTreeParams approx = with_cells(10);
  approx.eps = 0.5;
  const KdTree eps_tree(pts, approx);
  const KdTree scalar(pts, with_cells(10, KdScan::Scalar));
  const KdTree vector(pts, with_cells(10));
  const Points queries = test::uniform_cloud(50, 62, 1.1, Vec3::Zero());
  for (Eigen::Index i = 0; i < queries.rows(); ++i) {
    const Vec3 q = queries.row(i).transpose();
    std::uint32_t leaf = 5;
    EXPECT_EQ(no_cells.nearest_from(q, leaf), no_cells.nearest(q));
    std::uint32_t untouched = 12345;
    EXPECT_EQ(eps_tree.nearest_from(q, untouched), eps_tree.nearest(q));
    EXPECT_EQ(untouched, 12345u);
    std::uint32_t a = 3, b = 3;
    EXPECT_EQ(scalar.nearest_from(q, a), vector.nearest_from(q, b));  // same tree shape, same leaves
    EXPECT_EQ(a, b);
  }
  const KdTree empty(Points(0, 3), with_cells(10));
  std::uint32_t leaf = 9;
  double d2 = 0.0;
  EXPECT_EQ(empty.nearest_from(Vec3::Zero(), leaf, &d2), -1);
  EXPECT_EQ(leaf, 9u);
  EXPECT_EQ(d2, std::numeric_limits<double>::infinity());
  std::uint32_t bad = 0;
  EXPECT_THROW(vector.nearest_from(Vec3(std::nan(""), 0, 0), bad), Error);
  EXPECT_GT(KdTree(pts, with_cells(10)).memory_bytes(), no_cells.memory_bytes());
}

// With the AVX2 walk a tree keeps fans instead of per-node cells (so the tests above compare the two walks, not one
// walk twice): its size differs from the scalar tree's over the same nodes, and each holds more than the tree
// without either. One leaf (no inner node) gets no fans and walks by its cell.
TEST(KdTreeFromLeaf, VectorWalkKeepsFansInsteadOfCells) {
  if (!kd_scan_available(KdScan::Avx2)) GTEST_SKIP() << "no AVX2 on this CPU or build";
  const Points pts = test::uniform_cloud(5000, 71, 1.0, Vec3::Zero());
  KdTreeParams plain = with_cells(8, KdScan::Scalar);
  plain.cells = false;
  const std::size_t none = KdTree(pts, plain).memory_bytes();
  const std::size_t cells = KdTree(pts, with_cells(8, KdScan::Scalar)).memory_bytes();
  const std::size_t fans = KdTree(pts, with_cells(8, KdScan::Avx2)).memory_bytes();
  EXPECT_GT(cells, none);
  EXPECT_GT(fans, none);
  EXPECT_NE(fans, cells);
  const Points three = test::uniform_cloud(3, 72, 1.0, Vec3::Zero());
  const KdTree one_leaf(three, with_cells(8, KdScan::Avx2));
  std::uint32_t leaf = 0;
  for (Eigen::Index i = 0; i < three.rows(); ++i) EXPECT_EQ(one_leaf.nearest_from(three.row(i).transpose(), leaf), i);
}

}  // namespace
}  // namespace surfeledit
