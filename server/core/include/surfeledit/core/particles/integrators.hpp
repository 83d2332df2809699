// One time step of the particles (thesis §12.2.6-12.2.7, §12.3.5-12.3.6): a_i = (f_i - beta_0 v_i) s_i,
// alpha_i = (tau_i - beta_1 omega_i) s_i (Eq. 12.21-12.22), then Leapfrog or Euler-Cromer; orientations turn
// by theta = h omega (q <- q_theta q). Velocity control and "only grow" are applied here.
#pragma once

#include "surfeledit/core/particles/forces.hpp"

namespace surfeledit {

// Advances `state` by `h` under `forces` (computed at the current state); `scale` #P region scale.
void integrate(ParticleState& state, const SystemForces& forces, const Values& scale, const ParticleParams& params,
               double h);

}  // namespace surfeledit
