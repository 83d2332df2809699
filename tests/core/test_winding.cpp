// The generalized winding number (winding.hpp, docs/algorithms.md §4.6) against closed forms: one
// dipole by hand, a sampled sphere's inside/outside by its exact signed distance, the exact sum vs
// the tree, and invariance to where the set sits and to the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/winding.hpp"

namespace surfeledit {
namespace {


SampledSurfels sphere_surfels(double radius, double spacing, const Vec3& center = Vec3::Zero()) {
  Pose pose;
  pose.translation = center;
  SampleParams sp;
  sp.spacing = spacing;
  sp.seed = 4;
  return make_sphere(radius, pose)->sample(sp);
}

Points random_points(int n, double half, std::uint64_t seed, const Vec3& center = Vec3::Zero()) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  Points q(n, 3);
  for (int i = 0; i < n; ++i) q.row(i) = (center + Vec3(u(rng), u(rng), u(rng))).transpose();
  return q;
}

TEST(Winding, OneDipoleByHand) {
  // One surfel at the origin, normal +z, area a: at q = (0, 0, -h), n . (p - q) = h, so w = a / (4 pi h^2).
  Points p(1, 3), n(1, 3);
  p << 0, 0, 0;
  n << 0, 0, 1;
  Values a(1);
  a << 0.3;
  const WindingNumber w(p, n, a);
  EXPECT_NEAR(w.at(Vec3(0, 0, -2.0)), 0.3 / (4 * EIGEN_PI * 4.0), 1e-15);
  EXPECT_NEAR(w.at(Vec3(0, 0, 2.0)), -0.3 / (4 * EIGEN_PI * 4.0), 1e-15);
  EXPECT_EQ(w.at(Vec3(0, 0, 0)), 0.0);  // the surfel itself contributes nothing, never NaN
}

TEST(Winding, SampledSphereInsideOutsideAndAreas) {
  const double r = 0.5, h = 0.02;
  const SampledSurfels s = sphere_surfels(r, h);
  const Values a = surfel_areas(s.positions);
  EXPECT_NEAR(a.sum() / (4 * EIGEN_PI * r * r), 1.0, 0.08);
  const WindingNumber w(s.positions, s.normals, a);
  const Points q = random_points(4000, 1.0, 7);
  int tested = 0;
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    const double dist = Vec3(q.row(i).transpose()).norm() - r;  // exact signed distance
    if (std::abs(dist) < 2 * h) continue;
    ++tested;
    ASSERT_EQ(w.at(Vec3(q.row(i).transpose())) > 0.5, dist < 0) << q.row(i);
  }
  EXPECT_GT(tested, 3000);
}

TEST(Winding, TreeAgreesWithTheExactSum) {
  const SampledSurfels s = sphere_surfels(0.5, 0.03);
  const Values a = surfel_areas(s.positions);
  WindingParams exact;
  exact.beta = 0.0;
  const WindingNumber tree(s.positions, s.normals, a), sum(s.positions, s.normals, a, exact);
  const Points q = random_points(2000, 1.0, 9);
  const Values wt = tree.at(q, 1), ws = sum.at(q, 1);
  EXPECT_LT((wt - ws).cwiseAbs().maxCoeff(), 0.1);
  // Deterministic: the same values with every thread count.
  EXPECT_EQ((tree.at(q, 2) - wt).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Winding, IndependentOfWhereTheSetSits) {
  const Vec3 far(1e6, -1e6, 1e6);
  const SampledSurfels s0 = sphere_surfels(0.5, 0.04), s1 = sphere_surfels(0.5, 0.04, far);
  const Values a = surfel_areas(s0.positions);
  const WindingNumber w0(s0.positions, s0.normals, a), w1(s1.positions, s1.normals, a);
  const Points q = random_points(500, 1.0, 11);
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    const Vec3 p = q.row(i).transpose();
    EXPECT_NEAR(w0.at(p), w1.at(Vec3(p + far)), 1e-6);
  }
}

TEST(Winding, BadInputNamesTheField) {
  Points p = Points::Zero(2, 3), n = Points::Zero(3, 3);
  Values a = Values::Ones(2);
  try {
    WindingNumber w(p, n, a);
    FAIL() << "accepted mismatched normals";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "normals");
  }
}

}  // namespace
}  // namespace surfeledit
