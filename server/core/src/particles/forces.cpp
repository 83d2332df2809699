// Sum of the pair potentials per particle (each particle visits all its neighbours, so no two threads
// write the same row) and the stable time step from the summed stiffness bounds.
#include "surfeledit/core/particles/forces.hpp"

#include <cmath>
#include <limits>

#include "surfeledit/core/util.hpp"

namespace surfeledit {

void compute_forces(const ParticleState& s, const Neighbourhood& nb, const ParticleParams& p, SystemForces& out) {
  const Index n = s.size();
  out.force.setZero(n, 3);
  out.torque.setZero(n, 3);
  out.stiffness.setZero(n);
  Values energy = Values::Zero(n);
  const Points normals = s.normals();
  const bool drop = p.drop_dphi;
#pragma omp parallel for schedule(static) num_threads(resolve_threads(p.threads))
  for (Index i = 0; i < n; ++i) {
    const Vec3 xi = s.x.row(i).transpose(), ni = normals.row(i).transpose();
    Vec3 f = Vec3::Zero(), tau = Vec3::Zero();
    double e = 0.0, k = 0.0;
    for (std::int64_t c = nb.offsets[i]; c < nb.offsets[i + 1]; ++c) {
      const Index j = nb.indices[c];
      const Vec3 r = s.x.row(j).transpose() - xi;
      const WeightSample w = weight(p.weight, r.norm());
      if (w.phi == 0.0 && w.dphi == 0.0) continue;
      const Vec3 nj = normals.row(j).transpose();
      const auto add = [&](const PairTerm& t, double a, bool with_torque) {
        e += a * t.energy;
        f += a * t.force;
        if (with_torque) tau += a * t.torque;
        k += a * t.stiffness;
      };
      if (p.alpha_planarity > 0.0) {
        add(coplanarity(ni, r, w, drop), p.alpha_planarity, true);
        add(coplanarity(nj, r, w, drop), p.alpha_planarity, false);  // Phi_P of j's plane moves x_i only
      }
      if (p.alpha_normality > 0.0) add(conormality(ni, nj, r, w, drop), 2.0 * p.alpha_normality, true);
      if (p.alpha_circularity > 0.0) add(cocircularity(ni, nj, r, w, drop), 2.0 * p.alpha_circularity, true);
      if (p.alpha_repulsion > 0.0 && p.repulsion.kind != RepulsionKind::None)
        add(repulsion(p.repulsion, r, w), 2.0 * p.alpha_repulsion, false);
    }
    out.force.row(i) = f.transpose();
    out.torque.row(i) = tau.transpose();
    out.stiffness[i] = k;
    energy[i] = 0.5 * e;  // each unordered pair is visited from both ends
  }
  out.energy = energy.sum();
}

double stable_time_step(const SystemForces& forces, const Values& scale, const ParticleParams& p) {
  double lambda = 0.0, s_max = 0.0;
  for (Eigen::Index i = 0; i < forces.stiffness.size(); ++i) {
    lambda = std::max(lambda, 2.0 * scale[i] * forces.stiffness[i]);
    s_max = std::max(s_max, scale[i]);
  }
  const double b = s_max * std::max(p.damping, p.angular_damping);
  if (lambda == 0.0 && b == 0.0) return std::numeric_limits<double>::infinity();
  // Damped symplectic step x'' = -lambda x - b x' is stable for lambda h^2 + 2 b h < 4.
  return p.dt_safety * 4.0 / (b + std::sqrt(b * b + 4.0 * lambda));
}

}  // namespace surfeledit
