// Leapfrog and Euler-Cromer steps with damping, region scaling, velocity control and "only grow".
#include "surfeledit/core/particles/integrators.hpp"

#include <cmath>

#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// Rotation by the rotation vector `theta` (angle |theta| about theta / |theta|).
Eigen::Quaterniond rotation(const Vec3& theta) {
  const double angle = theta.norm();
  if (angle == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, theta / angle));
}

// New velocity of one degree of freedom group (linear or angular) after a kick by `force` (undamped,
// unscaled). `vel`: the stored velocity, `prev`: Leapfrog's previous half-step velocity.
Vec3 kick(const Vec3& vel, const Vec3& prev, const Vec3& force, double beta, double s, const ParticleParams& p,
          bool first, double h) {
  const bool leapfrog = p.integrator == ParticleIntegrator::Leapfrog;
  // Velocity at the force's time: Leapfrog extrapolates it from the two last half steps (Eq. 12.27).
  const Vec3 v_now = (leapfrog && !first) ? Vec3(1.5 * vel - 0.5 * prev) : vel;
  const Vec3 a = (force - beta * v_now) * s;
  Vec3 v = vel;
  if (p.velocity_control && a.dot(v) < 0.0) v.setZero();  // §12.3.5
  // Leapfrog starts with a half kick so that its velocities live at half steps.
  return v + ((leapfrog && first) ? 0.5 * h : h) * a;
}

}  // namespace

void integrate(ParticleState& s, const SystemForces& forces, const Values& scale, const ParticleParams& p, double h) {
  const Index n = s.size();
  const bool first = s.steps == 0;
#pragma omp parallel for schedule(static) num_threads(resolve_threads(p.threads))
  for (Index i = 0; i < n; ++i) {
    const Vec3 v = kick(s.v.row(i).transpose(), s.v_prev.row(i).transpose(), forces.force.row(i).transpose(),
                        p.damping, scale[i], p, first, h);
    const Vec3 w = kick(s.w.row(i).transpose(), s.w_prev.row(i).transpose(), forces.torque.row(i).transpose(),
                        p.angular_damping, scale[i], p, first, h);
    s.v_prev.row(i) = s.v.row(i);
    s.w_prev.row(i) = s.w.row(i);
    Vec3 move = h * v;
    if (p.only_grow) {  // §12.3.6: keep the part of the move along +n only
      const Vec3 ni = s.normal(i);
      move = std::max(0.0, move.dot(ni)) * ni;
      s.v.row(i) = (move / h).transpose();
    } else {
      s.v.row(i) = v.transpose();
    }
    s.w.row(i) = w.transpose();
    s.x.row(i) += move.transpose();
    s.q[i] = (rotation(h * w) * s.q[i]).normalized();
  }
  ++s.steps;
}

}  // namespace surfeledit
