// Projection onto the original surface (thesis §12.3.7) against exact geometry: a noisy sample of the unit
// sphere, points projected by the tangent plane of the nearest sample and by the MLS projection, distances
// measured to the exact sphere; and the final MLS projection of run_blend.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "particle_fixtures.hpp"
#include "surfeledit/core/particles/blend.hpp"
#include "surfeledit/core/particles/projection.hpp"

namespace surfeledit {
namespace {

using test::fibonacci_sphere;

// `count` samples of the unit sphere, each moved along its normal by a uniform offset in [-noise, noise];
// normals exact.
void noisy_sphere(int count, double noise, std::uint64_t seed, Points& x, Points& n) {
  fibonacci_sphere(count, 1.0, x, n);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  for (Eigen::Index i = 0; i < x.rows(); ++i) x.row(i) += u(rng) * n.row(i);
}

// `count` random points within `offset` of the unit sphere.
Points near_sphere(int count, double offset, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(-offset, offset);
  Points q(count, 3);
  for (int i = 0; i < count; ++i) {
    const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
    q.row(i) = (1.0 + u(rng)) * d.transpose();
  }
  return q;
}

TEST(Projection, MlsLandsCloserToTheExactSphereThanTheTangentPlane) {
  // 4,000 samples (spacing ~0.056) with radial noise up to 0.01; kernel h = 0.11 (~2 spacings).
  Points x, n;
  noisy_sphere(4000, 0.01, 7, x, n);
  const SurfaceProjector surface(x, n);
  const Points q = near_sphere(500, 0.03, 11);
  double tangent_sum = 0.0, mls_sum = 0.0, mls_max = 0.0, normal_min = 1.0;
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    const Vec3 p = q.row(i).transpose();
    tangent_sum += std::abs(surface.onto_tangent_plane(p).norm() - 1.0);
    Vec3 nm;
    const Vec3 m = surface.onto_mls(p, 0.11, &nm);
    const double err = std::abs(m.norm() - 1.0);
    mls_sum += err;
    mls_max = std::max(mls_max, err);
    normal_min = std::min(normal_min, nm.dot(m.normalized()));
  }
  const double tangent_mean = tangent_sum / q.rows(), mls_mean = mls_sum / q.rows();
  // The tangent plane of one sample carries its noise (mean |offset| 0.005); MLS averages ~100 samples.
  EXPECT_GT(tangent_mean, 0.004);
  EXPECT_LT(mls_mean, 0.4 * tangent_mean) << "tangent " << tangent_mean << " mls " << mls_mean;
  EXPECT_LT(mls_max, 0.006);  // below the noise amplitude 0.01
  EXPECT_GT(normal_min, 0.999);  // the MLS normal is the sphere's
}

TEST(Projection, QuadraticFitRemovesThePlaneBiasOnACurvedSurface) {
  // Exact samples, a wide kernel (h = 0.3 on R = 1): a plane through the weighted centroid lies ~h^2/(2R)
  // = 0.045 inside; the quadratic height field lands on the sphere.
  Points x, n;
  fibonacci_sphere(6000, 1.0, x, n);
  const SurfaceProjector surface(x, n);
  const Points q = near_sphere(200, 0.1, 3);
  for (Eigen::Index i = 0; i < q.rows(); ++i) {
    Vec3 nm;
    const Vec3 m = surface.onto_mls(q.row(i).transpose(), 0.3, &nm);
    EXPECT_NEAR(m.norm(), 1.0, 3e-3) << "query " << i;  // what a quadratic leaves: O(h^4 / R^3), ~0.0023
    EXPECT_GT(nm.dot(m.normalized()), 0.9999);
  }
}

TEST(Projection, RowsAreProjectedIndependentlyOfThreads) {
  Points x, n;
  noisy_sphere(2000, 0.01, 5, x, n);
  const SurfaceProjector surface(x, n);
  Points q = near_sphere(3000, 0.02, 9), qn = q.rowwise().normalized();
  Points a = q, an = qn, b = q, bn = qn;
  project_rows_mls(surface, 0.15, a, an, 1);
  project_rows_mls(surface, 0.15, b, bn, 2);
  EXPECT_TRUE(a == b);
  EXPECT_TRUE(an == bn);
  for (Eigen::Index i = 0; i < q.rows(); ++i)
    EXPECT_TRUE(a.row(i).isApprox(surface.onto_mls(q.row(i).transpose(), 0.15).transpose(), 0.0));
}

TEST(Projection, RunBlendEndsOnTheMlsSurfaceOfItsParticles) {
  // A noisy sphere of radius 20 mean radii as particles with no iterations: "tangent" leaves them where
  // they are, "mls" smooths them onto the surface they sample (closer to the exact sphere).
  Points x, n;
  noisy_sphere(5000, 0.01, 13, x, n);  // spacing ~0.05 on the unit sphere
  const double mean_radius = 0.05;
  BlendParams p;
  p.iterations = 0;
  p.threads = 1;
  p.projection = ProjectionKind::Tangent;
  const BlendRun still = run_blend(x, n, Points(), mean_radius, p);
  p.projection = ProjectionKind::Mls;
  const BlendRun mls = run_blend(x, n, Points(), mean_radius, p);
  ASSERT_EQ(mls.positions.rows(), x.rows());
  double e_still = 0.0, e_mls = 0.0, normal_min = 1.0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    e_still += std::abs(still.positions.row(i).norm() - 1.0) / x.rows();
    e_mls += std::abs(mls.positions.row(i).norm() - 1.0) / x.rows();
    normal_min = std::min(normal_min, mls.normals.row(i).dot(mls.positions.row(i).normalized()));
  }
  EXPECT_NEAR(e_still, 0.005, 0.0005);  // mean |uniform(-0.01, 0.01)|
  EXPECT_LT(e_mls, 0.5 * e_still) << "mls " << e_mls;
  EXPECT_GT(normal_min, 0.995);
}

TEST(Projection, RejectsABadKernelWidth) {
  BlendParams p;
  p.mls_width = 0.0;
  EXPECT_THROW(validate(p), Error);
  p.mls_width = NAN;
  EXPECT_THROW(validate(p), Error);
}

}  // namespace
}  // namespace surfeledit
