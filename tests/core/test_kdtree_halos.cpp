// The fans' halos of KdTree::nearest_from (kdtree_search.hpp's Halo): where the start leaf's fan's stop box does not
// hold the search ball but its halo box does, the walk searches the halo's nodes and stops. Checked where that
// happens most: queries above, below and between the surfaces of a thin plate with a ball close above it (the
// Robust detector's piercing scene, small), upright and tilted, at 1e6 offsets and 1e+-4 scales, from the near-path
// leaf and from the previous answer's leaf, leaves of 24 and of 96 (the detectors' trees: oriented node boxes and
// the turned frame); each answer is the root descent's (row and dist2 bits, which no walk and no halo touches) and a
// brute-force nearest row.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

constexpr double kHalf = 1.0;     // plate half width
constexpr double kThick = 0.075;  // plate half thickness
constexpr double kBall = 0.5;     // ball radius, its lowest point 0.02 above the plate
constexpr double kSpacing = 0.04;  // sample spacing

// Spacings across the plate's width at spacing h: a face has (m + 1)^2 samples, the first rows of plate_and_ball
// (both faces, then the ball).
int face_steps(double h) { return static_cast<int>(2.0 * kHalf / h); }

// Both faces of the plate at spacing h (jittered by h / 4) and a ball above it (Fibonacci points at about the same
// spacing), turned by `turn`, scaled by `scale` and moved by `offset`.
Points plate_and_ball(double h, const Eigen::Matrix3d& turn, double scale, const Vec3& offset) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-0.25 * h, 0.25 * h);
  std::vector<Vec3> p;
  const int m = face_steps(h);
  for (int side : {-1, 1})
    for (int i = 0; i <= m; ++i)
      for (int j = 0; j <= m; ++j)
        p.emplace_back(-kHalf + i * h + jitter(rng), -kHalf + j * h + jitter(rng), side * kThick);
  const int k = static_cast<int>(4.0 * M_PI * kBall * kBall / (h * h));
  const Vec3 centre(0.0, 0.0, kThick + kBall + 0.02);
  for (int i = 0; i < k; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / k, r = std::sqrt(1.0 - z * z), a = i * 2.399963229728653;
    p.push_back(centre + kBall * Vec3(r * std::cos(a), r * std::sin(a), z));
  }
  Points out(static_cast<Eigen::Index>(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = (scale * (turn * p[i]) + offset).transpose();
  return out;
}

// Brute force: the smallest squared distance from q to a row and whether `row` is at it (within `tol` relative, for
// the tree's local frame's rounding), both relative to `offset`.
void expect_brute_nearest(const Points& pts, const Vec3& q, Index row, double d2, const Vec3& offset) {
  double best = std::numeric_limits<double>::infinity();
  const Vec3 ql = q - offset;
  for (Eigen::Index i = 0; i < pts.rows(); ++i)
    best = std::min(best, (pts.row(i).transpose() - offset - ql).squaredNorm());
  const double tol = 1e-9 * best + 1e-300;
  ASSERT_GE(row, 0);
  EXPECT_NEAR((pts.row(row).transpose() - offset - ql).squaredNorm(), best, tol);
  EXPECT_NEAR(d2, best, tol);
}

TEST(KdTreeHalos, PlateAndBallQueriesFromEveryStartAgreeWithTheRootAndBruteForce) {
  std::vector<KdScan> scans{KdScan::Scalar};
  for (KdScan s : {KdScan::Avx2, KdScan::Avx512})
    if (kd_scan_available(s)) scans.push_back(s);
  const Eigen::Matrix3d tilted = Eigen::AngleAxisd(0.5, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  struct Case {
    Eigen::Matrix3d turn;
    double scale;
    Vec3 offset;
  };
  const std::vector<Case> cases = {{Eigen::Matrix3d::Identity(), 1.0, Vec3::Zero()},
                                   {tilted, 1.0, Vec3::Zero()},
                                   {Eigen::Matrix3d::Identity(), 1e-4, Vec3(1e6 * 1e-4, 0.0, -2e6 * 1e-4)},
                                   {tilted, 1e4, Vec3(1e6, -1e6, 1e6)}};
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> across(-0.9 * kHalf, 0.9 * kHalf);
  // Heights above the plate's top face (and as far below its bottom face and between its faces), from a hundredth of
  // the spacing to well beyond a leaf's width.
  const std::vector<double> heights = {0.0004, 0.004, 0.012, 0.03, 0.05, 0.08, 0.15, 0.3};
  for (const Case& c : cases) {
    const Points pts = plate_and_ball(kSpacing, c.turn, c.scale, c.offset);
    for (KdScan scan : scans) {
      for (int leaf_size : {24, 96}) {
        KdTreeParams params;
        params.leaf_size = leaf_size;
        params.cells = true;
        params.threads = 1;
        params.scan = scan;
        // Leaves of 96 as the detectors' trees: with oriented node boxes and the turned frame (which turns the tilted
        // plate upright in the tree, halos included).
        params.frames = params.align = leaf_size == 96;
        const KdTree tree(pts, params);
        std::uint32_t walking = 0;
        // Half the queries anywhere over the plate, half just off one of its points (whose nearest is that point, in
        // whichever leaf it lies: often one of a halo's, near the face of its box).
        const Eigen::Index per_face = (face_steps(kSpacing) + 1) * (face_steps(kSpacing) + 1);
        std::uniform_int_distribution<Eigen::Index> any_plate_point(0, 2 * per_face - 1);
        for (int i = 0; i < 160; ++i) {
          const double h = heights[static_cast<std::size_t>(i) % heights.size()];
          Vec3 local;
          if (i % 2 == 0) {
            const double z = i % 3 == 0 ? kThick + h : (i % 3 == 1 ? -kThick - h : kThick - std::min(h, kThick));
            local = Vec3(across(rng), across(rng), z);
          } else {
            const Vec3 p = c.turn.transpose() * (pts.row(any_plate_point(rng)).transpose() - c.offset) / c.scale;
            local = p + Vec3(1e-3 * h, -1e-3 * h, p.z() > 0.0 ? h : -h);
          }
          const Vec3 q = c.scale * (c.turn * local) + c.offset;
          double d_root = 0.0;
          const Index root = tree.nearest(q, &d_root);
          for (std::uint32_t start : {walking, ~0u}) {
            std::uint32_t leaf = start;
            double d = 0.0;
            const Index row = tree.nearest_from(q, leaf, &d);
            ASSERT_EQ(row, root) << "query " << i << " start " << start;
            ASSERT_EQ(d, d_root) << "query " << i << " start " << start;  // bit-identical
            if (start == walking) walking = leaf;
          }
          expect_brute_nearest(pts, q, root, d_root, c.offset);
        }
      }
    }
  }
}

}  // namespace
}  // namespace surfeledit
