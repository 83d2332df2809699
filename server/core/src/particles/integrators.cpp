// Leapfrog and Euler-Cromer steps with damping, region scaling, velocity control and "only grow".
#include "surfeledit/core/particles/integrators.hpp"

#include <cmath>

#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// Rotation by the rotation vector `theta` (angle a = |theta| about theta / a): (cos(a/2), sin(a/2)/a theta).
// A step turns a particle by a small angle, where both factors are short even series in x = (a/2)^2 (to
// x^4; the first omitted terms are below 1e-19 relative for a < 0.1): no square root, division or sincos.
Eigen::Quaterniond rotation(const Vec3& theta) {
  const double a2 = theta.squaredNorm();
  double c = 1.0, s = 0.5;  // cos(a/2), sin(a/2) / a
  if (a2 < 0.01) {
    const double x = 0.25 * a2;
    c = 1.0 - x * 0.5 * (1.0 - x * (1.0 / 12) * (1.0 - x * (1.0 / 30) * (1.0 - x * (1.0 / 56))));
    s = 0.5 * (1.0 - x * (1.0 / 6) * (1.0 - x * (1.0 / 20) * (1.0 - x * (1.0 / 42) * (1.0 - x * (1.0 / 72)))));
  } else {
    const double a = std::sqrt(a2);
    c = std::cos(0.5 * a);
    s = std::sin(0.5 * a) / a;
  }
  return Eigen::Quaterniond(c, s * theta.x(), s * theta.y(), s * theta.z());
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
    const Eigen::Quaterniond q = rotation(h * w) * s.q[i];
    // Back to unit length: near 1 (the product of unit quaternions, up to rounding) one Newton step of
    // 1 / sqrt(n2) leaves an error of order (n2 - 1)^2, without a square root or a division.
    const double n2 = q.squaredNorm();
    s.q[i].coeffs() = q.coeffs() * (std::abs(n2 - 1.0) < 1e-6 ? 1.5 - 0.5 * n2 : 1.0 / std::sqrt(n2));
  }
  ++s.steps;
}

}  // namespace surfeledit
