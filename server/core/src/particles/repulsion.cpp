// Spring, Gaussian and weight-based repulsion (thesis §12.2.4) as radial potentials Phi(rho), rho = |r|:
// the force on i is +grad_r Phi = Phi'(rho) / rho * r; the stiffness bound is |Phi''| + |Phi' / rho|.
#include "surfeledit/core/particles/repulsion.hpp"

namespace surfeledit {

PairTerm repulsion(const RepulsionParams& params, const Vec3& r, const WeightSample& w) {
  const RadialTerm radial = repulsion_radial(params, r.norm(), w);
  PairTerm t;
  t.energy = radial.energy;
  t.force = radial.d1_r * r;
  t.stiffness = radial.stiffness;
  return t;
}

}  // namespace surfeledit
