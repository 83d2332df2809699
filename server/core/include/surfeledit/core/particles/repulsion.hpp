// Repulsion between two particles (thesis §12.2.4, docs/algorithms.md §8): a radial potential Phi_R(|r|) of
// r = x_j - x_i whose force on i is -grad_{x_i} Phi_R (the extracted thesis formulas for the Gaussian and the
// weight-based force are not the gradients of their potentials; we use the gradients).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/particles/potentials.hpp"

namespace surfeledit {

enum class RepulsionKind : std::uint8_t {
  None = 0,
  Spring = 1,    // Phi = k (|r| - r0)^2: repels closer than r0, attracts beyond (Eq. 12.12-12.13)
  Gaussian = 2,  // Phi = A exp(-|r|^2 / (2 sigma^2)) (Eq. 12.14-12.15)
  Weight = 3,    // Phi = A phi(|r|)^2 (Eq. 12.16-12.17; the thesis found it best)
};
constexpr EnumNames<RepulsionKind, 4> names_of(RepulsionKind) {
  return {{{RepulsionKind::None, "none"}, {RepulsionKind::Spring, "spring"}, {RepulsionKind::Gaussian, "gaussian"},
           {RepulsionKind::Weight, "weight"}}};
}


struct RepulsionParams {
  RepulsionKind kind = RepulsionKind::Weight;  // which repulsion potential
  double amplitude = 1.0;                      // A (Gaussian, Weight) or k (Spring), >= 0
  double r0 = 1.0;                             // Spring: equilibrium distance (model units); above every
                                               // neighbour distance it only repels
  double sigma = 0.3;                          // Gaussian: standard deviation (model units), > 0; Witkin and
                                               // Heckbert suggest 0.3 sqrt(area / count)
};

// Phi_R at distance rho: value, Phi'(rho) / rho (the force on i is d1_r * r) and the stiffness bound
// |Phi''| + |Phi' / rho| (Spring: at a tiny distance when rho = 0). `w` is the weight at rho (Weight kind).
struct RadialTerm {
  double energy = 0.0;
  double d1_r = 0.0;
  double stiffness = 0.0;
};
// Weight-based repulsion A phi^2 (the branch-free case, also evaluated by the vectorised pair kernel).
inline RadialTerm weight_repulsion(double A, const WeightSample& w) {
  RadialTerm t;
  t.energy = A * w.phi * w.phi;
  t.d1_r = 2.0 * A * w.phi * w.dphi_r;
  const double d2 = 2.0 * A * (w.dphi * w.dphi + w.phi * w.ddphi);  // Phi''
  t.stiffness = std::abs(d2) + std::abs(t.d1_r);
  return t;
}
inline RadialTerm repulsion_radial(const RepulsionParams& params, double rho, const WeightSample& w) {
  RadialTerm t;
  const double A = params.amplitude;
  double d2 = 0.0;  // Phi''
  switch (params.kind) {
    case RepulsionKind::None: return t;
    case RepulsionKind::Spring: {
      const double e = rho - params.r0;
      t.energy = A * e * e;
      // At rho = 0 the direction is undefined: no force, and a stiffness as at a tiny distance.
      const double rho_safe = std::max(rho, 1e-9 * params.r0);
      t.d1_r = rho > 0.0 ? 2.0 * A * e / rho : 0.0;
      t.stiffness = 2.0 * A + 2.0 * A * std::abs(rho_safe - params.r0) / rho_safe;
      return t;
    }
    case RepulsionKind::Gaussian: {
      const double s2 = params.sigma * params.sigma;
      const double g = A * std::exp(-rho * rho / (2.0 * s2));
      t.energy = g;
      t.d1_r = -g / s2;
      d2 = (rho * rho / (s2 * s2) - 1.0 / s2) * g;
      break;
    }
    case RepulsionKind::Weight: return weight_repulsion(A, w);
  }
  t.stiffness = std::abs(d2) + std::abs(t.d1_r);
  return t;
}

// Phi_R for the pair and its force on i (torque zero). `w` is the weight at |r| (Weight kind only).
PairTerm repulsion(const RepulsionParams& params, const Vec3& r, const WeightSample& w);

}  // namespace surfeledit
