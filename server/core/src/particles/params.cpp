// Validation of the particle engine settings.
#include "surfeledit/core/particles/params.hpp"

#include <cmath>
#include <string>

#include "surfeledit/core/types.hpp"
#include "../param_checks.hpp"

namespace surfeledit {

void validate(const ParticleParams& p) {
  using param_checks::require;
  using param_checks::require_finite;
  require_finite(p.weight.radius > 0.0, "weight.radius", p.weight.radius, "> 0");
  require(p.weight.eps > 0.0 && p.weight.eps < 1.0, "weight.eps", p.weight.eps, "in (0, 1)");
  require(p.repulsion.amplitude >= 0.0, "repulsion.amplitude", p.repulsion.amplitude, ">= 0");
  require(p.repulsion.r0 > 0.0, "repulsion.r0", p.repulsion.r0, "> 0");
  require(p.repulsion.sigma > 0.0, "repulsion.sigma", p.repulsion.sigma, "> 0");
  require(p.alpha_repulsion >= 0.0, "alpha_repulsion", p.alpha_repulsion, ">= 0");
  require(p.alpha_planarity >= 0.0, "alpha_planarity", p.alpha_planarity, ">= 0");
  require(p.alpha_normality >= 0.0, "alpha_normality", p.alpha_normality, ">= 0");
  require(p.alpha_circularity >= 0.0, "alpha_circularity", p.alpha_circularity, ">= 0");
  require(p.damping >= 0.0, "damping", p.damping, ">= 0");
  require(p.angular_damping >= 0.0, "angular_damping", p.angular_damping, ">= 0");
  require(p.gamma >= 0.0, "gamma", p.gamma, ">= 0");
  require_finite(p.dt > 0.0, "dt", p.dt, "> 0");
  require(p.dt_safety > 0.0 && p.dt_safety <= 1.0, "dt_safety", p.dt_safety, "in (0, 1]");
  require(p.max_substeps >= 1, "max_substeps", p.max_substeps, ">= 1");
  require_finite(p.neighbour_skin >= 0.0, "neighbour_skin", p.neighbour_skin, ">= 0");
  require(p.split_below >= 0, "split_below", p.split_below, ">= 0");
  require(p.kill_above >= 0, "kill_above", p.kill_above, ">= 0");
  require(p.kill_above == 0 || p.kill_above > p.split_below, "kill_above", p.kill_above, "0 or > split_below");
  require(p.local_repulsion_steps >= 0, "local_repulsion_steps", p.local_repulsion_steps, ">= 0");
}

}  // namespace surfeledit
