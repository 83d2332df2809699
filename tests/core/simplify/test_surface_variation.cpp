// Surface variation sigma = l0 / (l0 + l1 + l2): ~0 on a plane, ~1/3 for isotropic noise, between for
// curved patches (smaller for flatter ones); per-surfel variation over k nearest neighbours.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/simplify/surface_variation.hpp"

namespace surfeledit {
namespace {

IndexList all_rows(Index n) {
  IndexList r(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) r[i] = i;
  return r;
}

TEST(SurfaceVariation, PlaneIsZeroAnywhereInSpace) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 a = Vec3(1, 2, 3).normalized(), b = a.unitOrthogonal(), origin(1e4, -3e4, 7e3);
  Points p(500, 3);
  for (Index i = 0; i < 500; ++i) p.row(i) = (origin + u(rng) * a + u(rng) * b).transpose();
  const Covariance c = covariance_of(p, all_rows(500));
  EXPECT_LT(c.variation(), 1e-9);
  EXPECT_NEAR(std::abs(c.eigenvectors.col(0).dot(a.cross(b))), 1.0, 1e-9);  // l0 axis = plane normal
}

TEST(SurfaceVariation, IsotropicNoiseIsAThird) {
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  Points p(20000, 3);
  for (Index i = 0; i < 20000; ++i) p.row(i) = Vec3(g(rng), g(rng), g(rng)).transpose();
  EXPECT_NEAR(surface_variation(p, all_rows(20000).data(), 20000), 1.0 / 3.0, 0.01);
}

TEST(SurfaceVariation, DegenerateSets) {
  Points p(3, 3);
  p << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  EXPECT_EQ(surface_variation(p, all_rows(3).data(), 3), 0.0);    // three points are planar
  EXPECT_EQ(surface_variation(p, all_rows(1).data(), 1), 0.0);    // one point
  Points same = Points::Constant(4, 3, 2.5);
  EXPECT_EQ(surface_variation(same, all_rows(4).data(), 4), 0.0);  // coincident points
}

TEST(SurfaceVariation, PerSurfelOnSpheresShrinksWithCurvature) {
  // Same spacing, k = 18: the neighbourhood of a small sphere bends more.
  double mean[2];
  int idx = 0;
  for (double radius : {0.3, 3.0}) {
    const SampledSurfels s = make_sphere(radius)->sample(SampleParams{0.03, 1, 0.25});
    const KdTree tree(s.positions);
    const Values v = surface_variation(s.positions, tree, 18, {}, 2);
    EXPECT_GE(v.minCoeff(), 0.0);
    EXPECT_LE(v.maxCoeff(), 1.0 / 3.0 + 1e-12);
    mean[idx++] = v.mean();
  }
  EXPECT_GT(mean[0], 4.0 * mean[1]);
  EXPECT_LT(mean[1], 0.01);
}

}  // namespace
}  // namespace surfeledit
