// Every particle force and torque against central finite differences of its potential (thesis §12.2.2-12.2.4):
// force on i = -dE/dx_i, torque on i = -dE/dtheta_i for a small rotation theta of particle i.
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "surfeledit/core/particles/forces.hpp"
#include "surfeledit/core/particles/repulsion.hpp"
#include "particle_fixtures.hpp"

namespace surfeledit {
namespace {

constexpr double kStep = 1e-6;

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

Vec3 rotated(const Vec3& n, const Vec3& theta) {
  return theta.norm() == 0.0 ? n : Eigen::AngleAxisd(theta.norm(), theta.normalized()) * n;
}

// -gradient of `energy` (a function of a 3-vector offset) at 0 by central differences.
Vec3 minus_gradient(const std::function<double(const Vec3&)>& energy) {
  Vec3 g;
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = kStep * Vec3::Unit(k);
    g[k] = -(energy(e) - energy(-e)) / (2.0 * kStep);
  }
  return g;
}

void expect_near(const Vec3& analytic, const Vec3& numeric, const char* what) {
  const double tol = 1e-6 * (1.0 + numeric.norm());
  EXPECT_LT((analytic - numeric).norm(), tol) << what << ": analytic " << analytic.transpose() << " numeric "
                                             << numeric.transpose();
}

// A pair potential of (n_i, n_j, r) for the finite differences.
using PairFn = std::function<PairTerm(const Vec3&, const Vec3&, const Vec3&, const WeightSample&)>;

void check_pair(const PairFn& fn, const WeightParams& wp, bool has_torque, const char* what) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.1, 0.9);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 ni = random_unit(rng), nj = random_unit(rng);
    const Vec3 r = u(rng) * wp.radius * random_unit(rng);
    const PairTerm t = fn(ni, nj, r, weight(wp, r.norm()));
    // x_i moves by e: r becomes r - e.
    const Vec3 f = minus_gradient([&](const Vec3& e) {
      const Vec3 re = r - e;
      return fn(ni, nj, re, weight(wp, re.norm())).energy;
    });
    expect_near(t.force, f, what);
    const Vec3 tau = minus_gradient([&](const Vec3& th) { return fn(rotated(ni, th), nj, r, weight(wp, r.norm())).energy; });
    expect_near(t.torque, has_torque ? tau : Vec3::Zero(), what);
    if (!has_torque) expect_near(tau, Vec3::Zero(), what);
  }
}

std::vector<WeightParams> weightings() {
  WeightParams compact, gauss;
  compact.radius = gauss.radius = 1.7;
  gauss.kind = WeightKind::CutGaussian;
  gauss.eps = 0.05;
  return {compact, gauss};
}

TEST(ParticleGradients, WeightDerivativesMatchFiniteDifferences) {
  for (const WeightParams& wp : weightings()) {
    for (double r = 0.05; r < wp.radius; r += 0.1) {
      const WeightSample w = weight(wp, r), a = weight(wp, r + kStep), b = weight(wp, r - kStep);
      EXPECT_NEAR(w.dphi, (a.phi - b.phi) / (2 * kStep), 1e-7);
      EXPECT_NEAR(w.ddphi, (a.dphi - b.dphi) / (2 * kStep), 1e-6);
      EXPECT_NEAR(w.dphi_r * r, w.dphi, 1e-12);
    }
    EXPECT_EQ(weight(wp, wp.radius).phi, 0.0);
  }
  EXPECT_NEAR(weight(weightings()[1], 1.7 - 1e-12).phi, 0.05, 1e-9);  // phi(d) = eps just inside d
}

TEST(ParticleGradients, CoplanarityForceAndTorque) {
  for (const WeightParams& wp : weightings())
    check_pair([](const Vec3& ni, const Vec3&, const Vec3& r, const WeightSample& w) { return coplanarity(ni, r, w); },
               wp, true, "co-planarity");
}

TEST(ParticleGradients, ConormalityForceAndTorque) {
  for (const WeightParams& wp : weightings())
    check_pair([](const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w) {
      return conormality(ni, nj, r, w);
    }, wp, true, "co-normality");
}

TEST(ParticleGradients, CocircularityForceAndTorque) {
  for (const WeightParams& wp : weightings())
    check_pair([](const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w) {
      return cocircularity(ni, nj, r, w);
    }, wp, true, "co-circularity");
}

TEST(ParticleGradients, RepulsionForces) {
  for (const WeightParams& wp : weightings()) {
    for (RepulsionKind kind : {RepulsionKind::Spring, RepulsionKind::Gaussian, RepulsionKind::Weight}) {
      RepulsionParams rp;
      rp.kind = kind;
      rp.amplitude = 2.5;
      rp.r0 = 1.2;
      rp.sigma = 0.4;
      check_pair([&](const Vec3&, const Vec3&, const Vec3& r, const WeightSample& w) { return repulsion(rp, r, w); },
                 wp, false, "repulsion");
    }
  }
}

TEST(ParticleGradients, RepulsionPushesApart) {
  RepulsionParams rp;
  const Vec3 r(0.3, 0.0, 0.0);  // j in +x of i: i must be pushed to -x
  for (RepulsionKind kind : {RepulsionKind::Spring, RepulsionKind::Gaussian, RepulsionKind::Weight}) {
    rp.kind = kind;
    EXPECT_LT(repulsion(rp, r, weight(WeightParams{}, 0.3)).force.x(), 0.0);
  }
}

// The whole system: compute_forces against finite differences of its total energy, all terms on.
TEST(ParticleGradients, SystemForcesAreMinusEnergyGradient) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 60;
  Points x(n, 3), nrm(n, 3);
  for (int i = 0; i < n; ++i) {
    x.row(i) << 2 * u(rng), 2 * u(rng), 0.3 * u(rng);
    nrm.row(i) << 0.3 * u(rng), 0.3 * u(rng), 1.0;
  }
  for (const WeightParams& wp : weightings()) {
    ParticleParams p;
    p.weight = wp;
    p.threads = 1;
    ParticleState s = ParticleState::from_surfels(x, nrm);
    const Neighbourhood nb = neighbours_kdtree(s.x, 3.0 * wp.radius);  // superset: phi is 0 beyond d
    SystemForces f;
    compute_forces(s, nb, p, f);
    const auto energy_at = [&](const ParticleState& t) {
      SystemForces g;
      compute_forces(t, nb, p, g);
      return g.energy;
    };
    for (Index i : {0, 7, 31}) {
      const Vec3 fx = minus_gradient([&](const Vec3& e) {
        ParticleState t = s;
        t.x.row(i) += e.transpose();
        return energy_at(t);
      });
      expect_near(f.force.row(i).transpose(), fx, "system force");
      const Vec3 tq = minus_gradient([&](const Vec3& th) {
        ParticleState t = s;
        t.q[i] = Eigen::Quaterniond(Eigen::AngleAxisd(th.norm(), th.norm() > 0 ? th.normalized() : Vec3::UnitZ())) * t.q[i];
        return energy_at(t);
      });
      expect_near(f.torque.row(i).transpose(), tq, "system torque");
    }
  }
}

// compute_forces evaluates each unordered pair once and sums in a fixed order: the same bits on 1 and 3
// threads (two different code paths), for every weighting, repulsion and drop_dphi; asymmetric
// neighbourhoods are refused.
TEST(ParticleGradients, SystemForcesDoNotDependOnThreads) {
  const ParticleState s = test::plane_patch(14, 0.3, 0.3, 0.3, 9);
  for (const WeightParams& wp : weightings())
    for (RepulsionKind kind : {RepulsionKind::None, RepulsionKind::Spring, RepulsionKind::Gaussian, RepulsionKind::Weight})
      for (bool drop : {false, true}) {
        ParticleParams p;
        p.weight = wp;
        p.weight.radius *= 2.0;
        p.repulsion.kind = kind;
        p.drop_dphi = drop;
        const Neighbourhood nb = neighbours_grid(s.x, p.weight.radius, 1);
        SystemForces one, three;
        p.threads = 1;
        compute_forces(s, nb, p, one);
        p.threads = 3;
        compute_forces(s, nb, p, three);
        EXPECT_TRUE(one.force == three.force && one.torque == three.torque && one.stiffness == three.stiffness &&
                    one.energy == three.energy)
            << "weight " << int(wp.kind) << " repulsion " << int(kind) << " drop " << drop;
        EXPECT_GT(one.energy, 0.0);
      }
  Neighbourhood bad = neighbours_grid(s.x, 2.0, 1);
  bad.indices[bad.offsets[5]] = bad.indices[bad.offsets[5] + 1];  // row 5 loses a neighbour, gets a repeat
  ParticleParams p;
  p.threads = 2;
  SystemForces f;
  EXPECT_THROW(compute_forces(s, bad, p, f), Error);
}

}  // namespace
}  // namespace surfeledit
