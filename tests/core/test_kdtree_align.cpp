// KdTreeParams::align (kdtree_align.cpp's choose_turn): a plane, a cylinder and a two-sided slab turned against the
// axes get a turned frame whose axes are orthonormal and fit the surface (the plane's normal is one of them), and
// every answer (nearest, nearest_from from any leaf, knn, radius, batches) is the brute-force one in world
// coordinates, at 1e6 offsets and 1e+-4 scales; the same surfaces upright and an isotropic cloud keep the world axes
// and give the same bits as a tree without align.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kdtree_truth.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

const Mat3 kTurn = Eigen::AngleAxisd(0.7, Vec3(0.4, -0.3, 0.85).normalized()).toRotationMatrix();

// The plane (or cylinder) sampled twice, the second copy `gap` spacings along its normal: a plate's two faces.
Points slab(int side, double h, double gap, double scale, const Vec3& offset, const Mat3& turn) {
  const Points top = test::turned_surface(side, h, false, scale, offset, turn);
  Points both(2 * top.rows(), 3);
  both << top, top.rowwise() + (gap * h * scale * (turn * Vec3::UnitZ())).transpose();
  return both;
}

// |dist2 - truth| allowed for a tree that computes in a turned frame: its coordinates are off by a few ulps of the
// model's size `size` (1e-15 relative), which moves a distance d by about d * 1e-15 * size.
double turned_tol(double truth, double size) {
  return 1e-9 * truth + 1e-13 * size * std::sqrt(truth) + 1e-28 * size * size;
}

TEST(KdTreeAlign, TurnedSurfacesGetTheirAxesAndBruteForceAnswers) {
  const double h = 0.01;
  for (const int shape : {0, 1, 2}) {  // plane, cylinder, slab
    for (const double scale : {1e-4, 1.0, 1e4}) {
      for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
        const Points pts = shape == 2 ? slab(70, h, 8.0, scale, offset, kTurn)
                                      : test::turned_surface(90, h, shape == 1, scale, offset, kTurn);
        const Points queries = test::queries_about(pts, 100, h, scale);
        const double size = 0.9 * scale;
        const Points rel = pts.rowwise() - offset.transpose();
        for (const KdScan scan : {KdScan::Scalar, KdScan::Auto}) {
          const KdTree tree(pts, test::nearest_params(scan, true, true));
          const Mat3 axes = tree.axes();
          ASSERT_LT((axes * axes.transpose() - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-14) << "orthonormal";
          ASSERT_GT((axes - Mat3::Identity()).cwiseAbs().maxCoeff(), 0.1) << "turned, shape " << shape;
          if (shape != 1) {
            // The surface's normal is one of the axes (to the search's 0.25-degree steps).
            const Vec3 normal = kTurn * Vec3::UnitZ();
            EXPECT_GT((axes * normal).cwiseAbs().maxCoeff(), std::cos(0.01)) << "shape " << shape;
          }
          const KnnResult batch = tree.knn(queries, 1), batch8 = tree.knn(queries, 8);
          for (Eigen::Index i = 0; i < queries.rows(); ++i) {
            const Vec3 q = queries.row(i).transpose();
            const Vec3 qr = q - offset;
            const std::vector<double> truth = test::brute_dist2(rel, qr);
            double d = 0.0;
            const Index r = tree.nearest(q, &d);
            ASSERT_GE(r, 0);
            // The row found is a nearest one in world coordinates, and its dist2 is its distance.
            EXPECT_NEAR((rel.row(r).transpose() - qr).squaredNorm(), truth.front(), turned_tol(truth.front(), size))
                << "shape " << shape << " scale " << scale << " query " << i;
            EXPECT_NEAR(d, truth.front(), turned_tol(truth.front(), size));
            ASSERT_EQ(batch.indices(i, 0), r);
            ASSERT_EQ(batch.dist2(i, 0), d);
            for (std::uint32_t start : {0u, 7u, 1000000u}) {
              std::uint32_t leaf = start;
              double f = 0.0;
              ASSERT_EQ(tree.nearest_from(q, leaf, &f), r) << "query " << i << " start " << start;
              ASSERT_EQ(f, d);
            }
            for (int j = 0; j < 8; ++j) {
              const Index rj = batch8.indices(i, j);
              EXPECT_NEAR((rel.row(rj).transpose() - qr).squaredNorm(), truth[j], turned_tol(truth[j], size)) << j;
              EXPECT_NEAR(batch8.dist2(i, j), truth[j], turned_tol(truth[j], size)) << j;
            }
            // Radius: every point well inside the ball is found, none well outside.
            const double radius = std::sqrt(truth[20]);
            IndexList idx;
            std::vector<double> d2;
            tree.radius(q, radius, idx, d2);
            std::size_t inside = 0, maybe = 0;
            for (double t : truth) {
              inside += t < radius * radius - turned_tol(t, size);
              maybe += t <= radius * radius + turned_tol(t, size);
            }
            EXPECT_GE(idx.size(), inside);
            EXPECT_LE(idx.size(), maybe);
            for (std::size_t j = 0; j < idx.size(); ++j)
              EXPECT_NEAR((rel.row(idx[j]).transpose() - qr).squaredNorm(), d2[j], turned_tol(d2[j], size));
          }
        }
      }
    }
  }
}

TEST(KdTreeAlign, UprightSurfacesAndIsotropicCloudsKeepTheWorldAxesAndTheirBits) {
  const double h = 0.01;
  const Points plate = slab(70, h, 8.0, 1.0, Vec3(3, -2, 1), Mat3::Identity());
  const Points cloud = test::random_cloud(20000, 93, 2.0, Vec3(1e6, 0, -1e6));
  for (const Points* pts : {&plate, &cloud}) {
    const Points queries = test::queries_about(*pts, 200, h, 1.0);
    const KdTree with(*pts, test::nearest_params(KdScan::Auto, true, true)),
        without(*pts, test::nearest_params(KdScan::Auto, true, false));
    ASSERT_EQ(with.axes(), Mat3::Identity());
    const KnnResult a = with.knn(queries, 4), b = without.knn(queries, 4);
    ASSERT_EQ(a.indices, b.indices);
    ASSERT_EQ(a.dist2, b.dist2);
  }
}

}  // namespace
}  // namespace surfeledit
