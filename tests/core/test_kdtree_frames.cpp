// KdTreeParams::frames (an oriented box per node, kdtree_build.cpp's build_frames): samples of planes and a cylinder
// turned against the axes, where the oriented boxes are kept and prune, queried near and far from the surface at
// 1e6 offsets and 1e+-4 scales. A tree with frames answers nearest, nearest_from (from every leaf) and knn(., 1)
// with the same row and dist2 bits as the same tree without frames, and its distance is the brute-force minimum.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "kdtree_truth.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

// A side x side lattice of spacing h on the plane z = 0 (or, `bent`, on a cylinder of radius side * h / 2 about
// the x axis), jittered by 1e-3 h (seeded), turned by a rotation no face of the axes' boxes survives, scaled and
// moved to `offset`.
Points turned_surface(int side, double h, bool bent, double scale, const Vec3& offset) {
  std::mt19937_64 rng(91);
  std::uniform_real_distribution<double> jitter(-1e-3 * h, 1e-3 * h);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Vec3(0.4, -0.3, 0.85).normalized()).toRotationMatrix();
  const double radius = 0.5 * side * h;
  Points p(side * side, 3);
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      const double u = (i - side / 2) * h + jitter(rng), v = (j - side / 2) * h + jitter(rng);
      Vec3 x(u, v, jitter(rng));
      if (bent) x = Vec3(u, radius * std::sin(v / radius), radius * (1.0 - std::cos(v / radius)));
      p.row(i * side + j) = (offset + scale * (turn * x)).transpose();
    }
  }
  return p;
}

// Queries at 0 to 40 spacings from the surface's middle region (either side), seeded.
Points queries_about(const Points& surface, int n, double h, double scale) {
  std::mt19937_64 rng(92);
  std::uniform_int_distribution<Eigen::Index> row(0, surface.rows() - 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0), far(0.0, 40.0);
  Points q(n, 3);
  for (int i = 0; i < n; ++i) {
    const Vec3 dir = Vec3(u(rng), u(rng), u(rng)).normalized();
    q.row(i) = surface.row(row(rng)) + (far(rng) * h * scale * dir).transpose();
  }
  return q;
}

KdTreeParams params(bool frames, KdScan scan) {
  KdTreeParams p;
  p.leaf_size = 128;
  p.threads = 1;
  p.cells = true;
  p.frames = frames;
  p.scan = scan;
  return p;
}

TEST(KdTreeFrames, SameAnswersAsWithoutFramesAndBruteForceOnTurnedSurfaces) {
  const double h = 0.01;
  for (const bool bent : {false, true}) {
    for (const double scale : {1e-4, 1.0, 1e4}) {
      for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
        const Points pts = turned_surface(90, h, bent, scale, offset);
        const Points queries = queries_about(pts, 120, h, scale);
        for (const KdScan scan : {KdScan::Scalar, KdScan::Auto}) {
          const KdTree with(pts, params(true, scan)), without(pts, params(false, scan));
          ASSERT_GT(with.memory_bytes(), without.memory_bytes());  // the frames are there
          const KnnResult batch_with = with.knn(queries, 1), batch_without = without.knn(queries, 1);
          for (Eigen::Index i = 0; i < queries.rows(); ++i) {
            const Vec3 q = queries.row(i).transpose();
            double dw = 0.0, dn = 0.0;
            const Index rw = with.nearest(q, &dw), rn = without.nearest(q, &dn);
            ASSERT_EQ(rw, rn) << "query " << i;
            ASSERT_EQ(dw, dn) << "query " << i;  // bit-identical
            ASSERT_EQ(batch_with.indices(i, 0), rn);
            ASSERT_EQ(batch_with.dist2(i, 0), batch_without.dist2(i, 0));
            // Brute force, relative to the offset so that the comparison is between small differences.
            const std::vector<double> truth = test::brute_dist2(pts.rowwise() - offset.transpose(), q - offset);
            EXPECT_NEAR(dw, truth.front(), 1e-9 * truth.front() + 1e-24 * scale * scale) << "query " << i;
            // From several leaves: the first, the winner's, and a stale one.
            for (std::uint32_t start : {0u, 7u, 1000000u}) {
              std::uint32_t lw = start, ln = start;
              double fw = 0.0, fn = 0.0;
              ASSERT_EQ(with.nearest_from(q, lw, &fw), rn) << "query " << i << " start " << start;
              ASSERT_EQ(without.nearest_from(q, ln, &fn), rn);
              ASSERT_EQ(fw, fn);
              ASSERT_EQ(lw, ln);
            }
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace surfeledit
