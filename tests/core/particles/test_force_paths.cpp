// compute_forces' compiled variants and its fused kernel: every instruction-set variant gives the same bits
// on one and several threads, and the fused, vectorised sums equal a brute-force sum of the per-term
// potentials (potentials.hpp, repulsion.hpp: an independent code path) over the neighbour pairs.
#include <gtest/gtest.h>

#include <cmath>

#include "particle_fixtures.hpp"
#include "surfeledit/core/particles/forces.hpp"
#include "surfeledit/core/particles/repulsion.hpp"

namespace surfeledit {
namespace {

std::vector<ParticleParams> all_kinds() {
  std::vector<ParticleParams> out;
  for (WeightKind wk : {WeightKind::Compact, WeightKind::CutGaussian})
    for (RepulsionKind rk : {RepulsionKind::None, RepulsionKind::Spring, RepulsionKind::Gaussian, RepulsionKind::Weight})
      for (bool drop : {false, true}) {
        ParticleParams p;
        p.weight.kind = wk;
        p.weight.radius = 2.3;
        p.weight.eps = 0.05;
        p.repulsion.kind = rk;
        p.repulsion.amplitude = 1.7;
        p.repulsion.r0 = 1.1;
        p.repulsion.sigma = 0.5;
        p.alpha_planarity = 0.8, p.alpha_normality = 1.3, p.alpha_circularity = 0.6, p.alpha_repulsion = 1.1;
        p.drop_dphi = drop;
        out.push_back(p);
      }
  return out;
}

bool same_bits(const SystemForces& a, const SystemForces& b) {
  return a.force == b.force && a.torque == b.torque && a.stiffness == b.stiffness && a.energy == b.energy;
}

TEST(ForcePaths, EveryVariantAndThreadCountGivesTheSameBits) {
  if (!force_path_available(ForcePath::Avx2)) GTEST_SKIP() << "no AVX2 variant on this CPU or build";
  // Rows of every length modulo 4 (the kernels run four lanes at a time, padded) and several blocks of 64.
  const ParticleState s = test::plane_patch(17, 0.35, 0.3, 0.3, 21);
  for (const ParticleParams& base : all_kinds()) {
    const Neighbourhood nb = neighbours_grid(s.x, base.weight.radius, 1);
    SystemForces reference;
    ParticleParams p = base;
    p.threads = 1;
    compute_forces(s, nb, p, reference, ForcePath::Baseline);
    ASSERT_GT(reference.energy, 0.0);
    for (ForcePath path : {ForcePath::Baseline, ForcePath::Avx2, ForcePath::Auto})
      for (int threads : {1, 3}) {
        SystemForces f;
        p.threads = threads;
        compute_forces(s, nb, p, f, path);
        EXPECT_TRUE(same_bits(f, reference)) << "path " << int(path) << " threads " << threads << " weight "
                                             << int(p.weight.kind) << " repulsion " << int(p.repulsion.kind);
      }
  }
}

TEST(ForcePaths, FusedKernelEqualsTheSumOfThePerTermPotentials) {
  const ParticleState s = test::plane_patch(9, 0.35, 0.4, 0.4, 33);
  for (const ParticleParams& p : all_kinds()) {
    const Neighbourhood nb = neighbours_grid(s.x, p.weight.radius, 1);
    SystemForces f;
    compute_forces(s, nb, p, f);
    double energy = 0.0, scale = 0.0;
    for (Index i = 0; i < s.size(); ++i) {
      const Vec3 xi = s.x.row(i).transpose(), ni = s.normal(i);
      Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
      double stiffness = 0.0;
      for (std::int64_t c = nb.offsets[i]; c < nb.offsets[i + 1]; ++c) {
        const Index j = nb.indices[c];
        const Vec3 nj = s.normal(j), r = s.x.row(j).transpose() - xi;
        const WeightSample w = weight(p.weight, r.norm());
        // E_ij = 2 a_R Phi_R + a_P (Phi_P(n_i) + Phi_P(n_j)) + 2 a_N Phi_N + 2 a_C Phi_C; Phi_P(n_j) is
        // j's co-planarity with r -> -r, whose force on i is minus its force on j and whose torque on i is 0.
        const PairTerm pi = coplanarity(ni, r, w, p.drop_dphi), pj = coplanarity(nj, -r, w, p.drop_dphi);
        const PairTerm pn = conormality(ni, nj, r, w, p.drop_dphi), pc = cocircularity(ni, nj, r, w, p.drop_dphi);
        const PairTerm pr = repulsion(p.repulsion, r, w);
        const double aR = p.repulsion.kind == RepulsionKind::None ? 0.0 : p.alpha_repulsion;
        if (j > i)
          energy += 2 * aR * pr.energy + p.alpha_planarity * (pi.energy + pj.energy) +
                    2 * p.alpha_normality * pn.energy + 2 * p.alpha_circularity * pc.energy;
        force += 2 * aR * pr.force + p.alpha_planarity * (pi.force - pj.force) + 2 * p.alpha_normality * pn.force +
                 2 * p.alpha_circularity * pc.force;
        torque += p.alpha_planarity * pi.torque + 2 * p.alpha_normality * pn.torque + 2 * p.alpha_circularity * pc.torque;
        // The stiffness bound: a_P twice co-planarity's (it is the same for n_i and n_j), the others doubled.
        if (w.phi != 0.0 || w.dphi != 0.0)
          stiffness += 2 * aR * pr.stiffness + 2 * p.alpha_planarity * pi.stiffness +
                       2 * p.alpha_normality * pn.stiffness + 2 * p.alpha_circularity * pc.stiffness;
      }
      scale = std::max({scale, force.norm(), torque.norm()});
      const double tol = 1e-11 * (1.0 + force.norm() + torque.norm());
      EXPECT_LT((f.force.row(i).transpose() - force).norm(), tol) << "row " << i;
      EXPECT_LT((f.torque.row(i).transpose() - torque).norm(), tol) << "row " << i;
      EXPECT_NEAR(f.stiffness[i], stiffness, 1e-11 * (1.0 + stiffness)) << "row " << i;
    }
    EXPECT_GT(scale, 1e-3);  // the sums are not trivially zero
    EXPECT_NEAR(f.energy, energy, 1e-11 * (1.0 + std::abs(energy)))
        << "weight " << int(p.weight.kind) << " repulsion " << int(p.repulsion.kind) << " drop " << p.drop_dphi;
  }
}

}  // namespace
}  // namespace surfeledit
