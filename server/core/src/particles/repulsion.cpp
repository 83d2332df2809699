// Spring, Gaussian and weight-based repulsion (thesis §12.2.4) as radial potentials Phi(rho), rho = |r|:
// the force on i is +grad_r Phi = Phi'(rho) / rho * r; the stiffness bound is |Phi''| + |Phi' / rho|.
#include "surfeledit/core/particles/repulsion.hpp"

#include <algorithm>
#include <cmath>

namespace surfeledit {

PairTerm repulsion(const RepulsionParams& params, const Vec3& r, const WeightSample& w) {
  PairTerm t;
  const double rho = r.norm(), A = params.amplitude;
  double d1_r = 0.0, d2 = 0.0;  // Phi'/rho and Phi''
  switch (params.kind) {
    case RepulsionKind::None: return t;
    case RepulsionKind::Spring: {
      const double e = rho - params.r0;
      t.energy = A * e * e;
      // At rho = 0 the direction is undefined: no force, and a stiffness as at a tiny distance.
      const double rho_safe = std::max(rho, 1e-9 * params.r0);
      d1_r = rho > 0.0 ? 2.0 * A * e / rho : 0.0;
      d2 = 2.0 * A;
      t.stiffness = d2 + 2.0 * A * std::abs(rho_safe - params.r0) / rho_safe;
      t.force = d1_r * r;
      return t;
    }
    case RepulsionKind::Gaussian: {
      const double s2 = params.sigma * params.sigma;
      const double g = A * std::exp(-rho * rho / (2.0 * s2));
      t.energy = g;
      d1_r = -g / s2;
      d2 = (rho * rho / (s2 * s2) - 1.0 / s2) * g;
      break;
    }
    case RepulsionKind::Weight:
      t.energy = A * w.phi * w.phi;
      d1_r = 2.0 * A * w.phi * w.dphi_r;
      d2 = 2.0 * A * (w.dphi * w.dphi + w.phi * w.ddphi);
      break;
  }
  t.force = d1_r * r;
  t.stiffness = std::abs(d2) + std::abs(d1_r);
  return t;
}

}  // namespace surfeledit
