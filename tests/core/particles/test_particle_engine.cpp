// Particle engine behaviour with independent truths: damped energy decay, analytic planes and spheres,
// repulsion spreading a clump, neighbourhoods, determinism, region scaling, split / kill, MLS.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "particle_fixtures.hpp"
#include "surfeledit/core/particles/engine.hpp"
#include "surfeledit/core/particles/integrators.hpp"

namespace surfeledit {
namespace {

using test::fibonacci_sphere;
using test::plane_patch;

ParticleParams base_params() {
  ParticleParams p;
  p.weight.radius = 3.6;  // ~40 neighbours at spacing 1
  p.dt = 0.05;
  p.threads = 1;
  return p;
}

// Coefficient of variation of the nearest-neighbour distances.
double nn_spread(const Points& x) {
  std::vector<double> d(x.rows(), 1e300);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index j = 0; j < x.rows(); ++j)
      if (i != j) d[i] = std::min(d[i], (x.row(i) - x.row(j)).norm());
  double mean = 0, var = 0;
  for (double v : d) mean += v / d.size();
  for (double v : d) var += (v - mean) * (v - mean) / d.size();
  return std::sqrt(var) / mean;
}

TEST(ParticleEngine, DampedSystemLosesEnergy) {
  for (ParticleIntegrator integ : {ParticleIntegrator::Leapfrog, ParticleIntegrator::EulerCromer}) {
    ParticleParams p = base_params();
    p.integrator = integ;
    p.velocity_control = false;
    ParticleEngine engine(plane_patch(12, 0.2, 0.3, 0.3, 1), Points(), p);
    const double e0 = engine.energy();
    double e = e0;
    for (int it = 0; it < 100; ++it) {
      const StepReport r = engine.step();
      EXPECT_LE(r.energy, e0 * (1 + 1e-12));
      e = r.energy;
    }
    EXPECT_LT(e, 0.5 * e0) << "integrator " << int(integ);
  }
}

TEST(ParticleEngine, FlatPlaneStaysFlat) {
  ParticleParams p = base_params();
  ParticleEngine engine(plane_patch(10, 0.3, 0.0, 0.0, 2), Points(), p);
  for (int it = 0; it < 30; ++it) engine.step();
  EXPECT_LT(engine.state().x.col(2).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(engine.state().normals().col(2).minCoeff(), 1.0 - 1e-12);
}

TEST(ParticleEngine, SphereParticlesStayOnTheSphere) {
  Points x, n;
  fibonacci_sphere(800, 5.0, x, n);  // spacing ~0.63
  ParticleParams p = base_params();
  p.weight.radius = 1.6;
  p.project_tangent = true;
  ParticleEngine engine(ParticleState::from_surfels(x, n), Points(), p);
  engine.set_surface(x, n);
  for (int it = 0; it < 30; ++it) engine.step();
  const Values radius = engine.state().x.rowwise().norm();
  // The nearest tangent plane is off the sphere by at most ~ spacing^2 / (2 R).
  EXPECT_LT((radius.array() - 5.0).abs().maxCoeff(), 0.05);
  engine.project_mls(0.4);  // plane-fit MLS is biased inwards by ~ h^2 / (2 R) = 0.016
  const Values after = engine.state().x.rowwise().norm();
  EXPECT_LT((after.array() - 5.0).abs().maxCoeff(), 0.02);
}

TEST(ParticleEngine, RepulsionSpreadsAClump) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points x(150, 3), n(150, 3);
  for (int i = 0; i < 150; ++i) {
    x.row(i) << 4 * u(rng), 4 * u(rng), 0.0;
    n.row(i) << 0, 0, 1;
  }
  ParticleParams p = base_params();
  p.weight.radius = 1.5;
  p.alpha_planarity = p.alpha_normality = p.alpha_circularity = 0.0;
  p.repulsion.r0 = 1.5;     // spring: pure repulsion inside the neighbourhood
  p.repulsion.sigma = 0.5;  // Gaussian
  p.repulsion.amplitude = 5.0;
  p.dt = 0.2;
  p.neighbours = NeighbourMode::RecomputeGrid;  // particles leave their starting neighbourhoods
  const double before = nn_spread(x);
  EXPECT_GT(before, 0.5);
  for (RepulsionKind kind : {RepulsionKind::Spring, RepulsionKind::Gaussian, RepulsionKind::Weight}) {
    p.repulsion.kind = kind;
    ParticleEngine engine(ParticleState::from_surfels(x, n), Points(), p);
    for (int it = 0; it < 300; ++it) engine.step();
    const double after = nn_spread(engine.state().x);
    EXPECT_LT(after, 0.05) << "repulsion " << int(kind) << ": nearest-neighbour spread " << before << " -> " << after;
  }
}

TEST(ParticleEngine, GridAndKdTreeNeighbourhoodsAgree) {
  const ParticleState s = plane_patch(15, 0.4, 0.5, 0.0, 4);
  const Neighbourhood a = neighbours_kdtree(s.x, 2.5, 1), b = neighbours_grid(s.x, 2.5, 2);
  EXPECT_EQ(a.offsets, b.offsets);
  EXPECT_EQ(a.indices, b.indices);
}

TEST(ParticleEngine, ResultsDoNotDependOnThreadsOrNeighbourStructure) {
  Points first;
  for (NeighbourMode mode : {NeighbourMode::Cached, NeighbourMode::RecomputeGrid, NeighbourMode::RecomputeKdTree})
    for (int threads : {1, 2}) {
      ParticleParams p = base_params();
      p.neighbours = mode;
      p.threads = threads;
      ParticleEngine engine(plane_patch(10, 0.2, 0.2, 0.2, 5), Points(), p);
      engine.step();  // one step: every mode still uses the starting neighbourhood
      if (first.size() == 0) first = engine.state().x;
      EXPECT_TRUE(engine.state().x == first) << "mode " << int(mode) << " threads " << threads;
    }
}

TEST(ParticleEngine, RegionScaling) {
  Points x(3, 3), rigid(1, 3);
  x << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  rigid << 0, 0, 0;
  const Values s = region_scale(x, rigid, 2.0);
  EXPECT_DOUBLE_EQ(s[0], 0.0);
  EXPECT_DOUBLE_EQ(s[1], 0.25);
  EXPECT_DOUBLE_EQ(s[2], 1.0);
  EXPECT_TRUE(region_scale(x, Points(), 2.0).isOnes());
}

TEST(ParticleEngine, OnlyGrowMovesAlongThePositiveNormal) {
  ParticleParams p = base_params();
  p.only_grow = true;
  p.dt = 0.01;
  const ParticleState s0 = plane_patch(10, 0.2, 0.3, 0.0, 6);
  ParticleEngine engine(s0, Points(), p);
  for (int it = 0; it < 10; ++it) {
    const ParticleState before = engine.state();
    EXPECT_EQ(engine.step().substeps, 1);
    for (Index i = 0; i < before.size(); ++i) {
      const Vec3 d = (engine.state().x.row(i) - before.x.row(i)).transpose(), n = before.normal(i);
      EXPECT_GE(d.dot(n), -1e-15);
      EXPECT_LT((d - d.dot(n) * n).norm(), 1e-12);
    }
  }
}

TEST(ParticleEngine, SplitsSparseAndKillsCrowdedParticles) {
  ParticleParams p = base_params();
  p.weight.radius = 1.5;  // 8 neighbours on the unit grid inside
  p.kill_above = 20;
  p.split_below = 4;  // the 4 corners have 3 neighbours
  ParticleState s = plane_patch(8, 0.0, 0.0, 0.0, 7);
  const Index n0 = s.size();
  for (int k = 0; k < 30; ++k) s.append_copy(27, s.x.row(27).transpose() + Vec3(0.01 * k, 0.02, 0));  // crowd
  ParticleEngine engine(s, Points(), p);
  const StepReport r = engine.step();
  EXPECT_EQ(r.split, 4);
  EXPECT_GT(r.killed, 0);
  EXPECT_EQ(engine.state().size(), n0 + 30 + r.split - r.killed);
}

TEST(ParticleEngine, MlsProjectsOntoPlaneAndSphere) {
  Points x, n;
  fibonacci_sphere(3000, 1.0, x, n);
  const SurfaceProjector sphere(x, n);
  for (int i = 0; i < 3000; i += 97) {
    const Vec3 q = (1.0 + ((i % 2) ? 0.05 : -0.05)) * x.row(i).transpose();
    EXPECT_NEAR(sphere.onto_mls(q, 0.08).norm(), 1.0, 5e-3);
  }
  const ParticleState plane = plane_patch(10, 0.3, 0.0, 0.0, 8);
  const SurfaceProjector flat(plane.x, plane.normals());
  EXPECT_NEAR(flat.onto_mls(Vec3(4.3, 5.1, 0.7), 1.0).z(), 0.0, 1e-12);
  EXPECT_NEAR(flat.onto_tangent_plane(Vec3(4.3, 5.1, 0.7)).z(), 0.0, 1e-12);
}

TEST(ParticleEngine, RejectsBadSettings) {
  ParticleParams p = base_params();
  p.dt = -1;
  EXPECT_THROW(ParticleEngine(plane_patch(3, 0, 0, 0, 1), Points(), p), Error);
  p = base_params();
  p.project_tangent = true;
  ParticleEngine engine(plane_patch(3, 0, 0, 0, 1), Points(), p);
  EXPECT_THROW(engine.step(), Error);  // no original surface
}

// The integrator turns a particle by theta = h omega: against Eigen's angle-axis rotation (cos / sin), for
// angles on both sides of where the integrator switches from its series to cos and sin (a = 0.1).
TEST(ParticleEngine, RotationStepEqualsTheAngleAxisRotation) {
  ParticleParams p;
  p.integrator = ParticleIntegrator::EulerCromer;
  p.velocity_control = false;
  p.damping = p.angular_damping = 0.0;
  const double h = 0.5;
  for (double angle : {0.0, 1e-9, 1e-4, 0.01, 0.05, 0.0999, 0.1001, 0.7, 2.5}) {
    const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
    ParticleState s = ParticleState::from_surfels(Points::Zero(1, 3), Vec3(0.2, 0.1, 1.0).transpose());
    const Eigen::Quaterniond q0 = s.q[0];
    s.w.row(0) = (angle / h) * axis.transpose();
    SystemForces f;
    f.force = f.torque = Points::Zero(1, 3);
    integrate(s, f, Values::Ones(1), p, h);
    const Eigen::Quaterniond truth = Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)) * q0;
    EXPECT_LT((s.q[0].coeffs() - truth.coeffs()).norm(), 1e-15) << "angle " << angle;
    EXPECT_NEAR(s.q[0].norm(), 1.0, 1e-15) << "angle " << angle;
  }
}

}  // namespace
}  // namespace surfeledit
