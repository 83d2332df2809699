// Largest stable time step per integrator and weighting, found by a sweep of the raw integrator, against the
// engine's stable-step bound; above the bound the engine sub-steps or refuses instead of diverging.
#include <gtest/gtest.h>

#include <cstdio>

#include "particle_fixtures.hpp"
#include "surfeledit/core/particles/engine.hpp"
#include "surfeledit/core/particles/integrators.hpp"

namespace surfeledit {
namespace {

ParticleParams sweep_params(ParticleIntegrator integ, WeightKind kind) {
  ParticleParams p;
  p.weight.radius = 3.6;  // ~40 neighbours at spacing 1 (thesis Table 12.1)
  p.weight.kind = kind;
  p.integrator = integ;
  p.velocity_control = false;  // the bare integrator
  p.threads = 1;
  return p;
}

ParticleState sweep_state() { return test::plane_patch(12, 0.2, 0.3, 0.3, 21); }

// 200 unguarded steps of dt: false when the energy grows tenfold, a value turns non-finite or a particle
// travels further than 10 spacings.
bool stays_bounded(const ParticleParams& p, double dt) {
  ParticleState s = sweep_state();
  const Points x0 = s.x;
  const Neighbourhood nb = neighbours_kdtree(s.x, p.weight.radius, 1);
  const Values scale = Values::Ones(s.size());
  SystemForces f;
  compute_forces(s, nb, p, f);
  const double e0 = f.energy;
  for (int it = 0; it < 200; ++it) {
    integrate(s, f, scale, p, dt);
    compute_forces(s, nb, p, f);
    if (!std::isfinite(f.energy) || f.energy > 10.0 * e0 || (s.x - x0).rowwise().norm().maxCoeff() > 10.0) return false;
  }
  return true;
}

double largest_stable_dt(const ParticleParams& p) {
  double last = 0.0;
  for (double dt = 0.005; dt < 20.0; dt *= 1.1) {
    if (!stays_bounded(p, dt)) break;
    last = dt;
  }
  return last;
}

TEST(ParticleStability, BoundIsBelowTheMeasuredLimitAndEngineSubStepsOrRefuses) {
  for (ParticleIntegrator integ : {ParticleIntegrator::Leapfrog, ParticleIntegrator::EulerCromer})
    for (WeightKind kind : {WeightKind::Compact, WeightKind::CutGaussian}) {
      ParticleParams p = sweep_params(integ, kind);
      const double measured = largest_stable_dt(p);
      ParticleEngine probe(sweep_state(), Points(), p);
      const double bound = probe.stable_dt();
      std::printf("[ stability ] %s %s: largest stable dt %.4f, engine bound %.4f (ratio %.2f)\n",
                  integ == ParticleIntegrator::Leapfrog ? "leapfrog" : "euler-cromer",
                  kind == WeightKind::Compact ? "compact" : "cut-gaussian", measured, bound, measured / bound);
      EXPECT_GT(measured, 0.0);
      EXPECT_LE(bound, measured);
      EXPECT_GT(bound, measured / 20.0);  // not uselessly small

      // Twice the measured limit: raw integration diverges, the engine sub-steps and stays bounded...
      p.dt = 2.0 * measured;
      EXPECT_FALSE(stays_bounded(p, p.dt));
      ParticleEngine engine(sweep_state(), Points(), p);
      const double e0 = engine.energy();
      int substeps = 0;
      for (int it = 0; it < 100; ++it) substeps = std::max(substeps, engine.step().substeps);
      EXPECT_GT(substeps, 1);
      EXPECT_TRUE(engine.state().x.allFinite());
      EXPECT_LT(engine.energy(), e0);
      // ...or refuses and changes nothing.
      p.policy = StepPolicy::Refuse;
      ParticleEngine strict(sweep_state(), Points(), p);
      const Points before = strict.state().x;
      try {
        strict.step();
        ADD_FAILURE() << "expected a refusal";
      } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::Conflict);
        EXPECT_EQ(e.field(), "dt");
      }
      EXPECT_TRUE(strict.state().x == before);
    }
}

}  // namespace
}  // namespace surfeledit
