// KdTree::count_within (how many points lie strictly closer than a distance, counted up to a limit) against brute
// force: random clouds at 1e6 offsets and 1e+-4 scales, a lattice with every point three times (distances equal to
// the bound must not count), every limit from 0 past the true count, each leaf scan this CPU has; bad arguments.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "kdtree_truth.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

using test::brute_dist2;
using test::random_cloud;

// The scans this CPU has (the baseline one always).
std::vector<KdScan> scans() {
  std::vector<KdScan> out{KdScan::Scalar};
  for (KdScan s : {KdScan::Avx2, KdScan::Avx512})
    if (kd_scan_available(s)) out.push_back(s);
  return out;
}

KdTreeParams leaves_of(int leaf, KdScan scan) {
  KdTreeParams p;
  p.leaf_size = leaf;
  p.scan = scan;
  return p;
}

// min(limit, the number of brute-force squared distances below max_dist2), for every limit up to the true count + 2.
void expect_counts(const KdTree& tree, const Points& pts, const Vec3& q, double max_dist2) {
  const std::vector<double> d2 = brute_dist2(pts, q);
  const Index truth = static_cast<Index>(std::count_if(d2.begin(), d2.end(), [&](double v) { return v < max_dist2; }));
  for (Index limit = 0; limit <= truth + 2; limit += std::max<Index>(1, truth / 7))
    ASSERT_EQ(tree.count_within(q, max_dist2, limit), std::min(limit, truth))
        << "limit " << limit << " max_dist2 " << max_dist2;
  EXPECT_EQ(tree.count_within(q, max_dist2, static_cast<Index>(pts.rows()) + 5), truth);
}

TEST(KdTreeCount, MatchesBruteForceAtOffsetsAndScales) {
  for (const double scale : {1e-4, 1.0, 1e4}) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
      const Points pts = random_cloud(1500, 3, scale, offset * scale);
      const Points queries = random_cloud(40, 4, 1.2 * scale, offset * scale);
      for (KdScan scan : scans()) {
        for (int leaf : {1, 10, 96}) {
          const KdTree tree(pts, leaves_of(leaf, scan));
          for (Eigen::Index i = 0; i < queries.rows(); ++i) {
            const Vec3 q = queries.row(i).transpose();
            for (const double r : {0.0, 0.05, 0.3, 3.0}) expect_counts(tree, pts, q, r * r * scale * scale);
            expect_counts(tree, pts, q, std::numeric_limits<double>::infinity());
          }
        }
      }
    }
  }
}

// Lattice points at exactly the bound's distance do not count (strict), duplicates count each time.
TEST(KdTreeCount, BoundIsStrictOnALatticeWithDuplicates) {
  constexpr int m = 6;
  Points pts(3 * m * m * m, 3);
  for (int i = 0; i < m * m * m; ++i)
    for (int c = 0; c < 3; ++c) pts.row(c * m * m * m + i) << i % m, (i / m) % m, i / (m * m);
  for (KdScan scan : scans()) {
    for (int leaf : {1, 4, 16}) {
      const KdTree tree(pts, leaves_of(leaf, scan));
      const Vec3 q(2.0, 3.0, 2.0);  // a lattice point: 3 copies at 0, 18 at 1, 36 at 2 (squared)
      EXPECT_EQ(tree.count_within(q, 1.0, 1000), 3);
      EXPECT_EQ(tree.count_within(q, std::nextafter(1.0, 2.0), 1000), 21);
      EXPECT_EQ(tree.count_within(q, 2.0, 1000), 21);
      EXPECT_EQ(tree.count_within(q, 0.0, 1000), 0);
      for (const double r2 : {0.5, 1.5, 2.5, 3.5, 8.0, 100.0}) expect_counts(tree, pts, Vec3(2.5, 1.0, 3.5), r2);
    }
  }
}

TEST(KdTreeCount, RejectsBadArgumentsAndCountsAnEmptyTree) {
  const Points pts = random_cloud(50, 1);
  const KdTree tree(pts);
  for (const double bad : {-1.0, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      tree.count_within(Vec3::Zero(), bad, 3);
      ADD_FAILURE() << "accepted max_dist2 " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "max_dist2");
    }
  }
  try {
    tree.count_within(Vec3::Zero(), 1.0, -1);
    ADD_FAILURE() << "accepted limit -1";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "limit");
  }
  try {
    tree.count_within(Vec3(std::numeric_limits<double>::infinity(), 0, 0), 1.0, 3);
    ADD_FAILURE() << "accepted an infinite query";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "query");
  }
  const KdTree empty{Points(0, 3)};
  EXPECT_EQ(empty.count_within(Vec3::Zero(), 1.0, 3), 0);
}

}  // namespace
}  // namespace surfeledit
