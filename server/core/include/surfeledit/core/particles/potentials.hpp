// The three surface potentials of oriented particles (thesis §12.2.2-12.2.3, docs/algorithms.md §8) for one
// ordered pair (i, j), r = x_j - x_i, with their exact forces and torques on particle i:
//   co-planarity  Phi_P = (n_i . r)^2 phi(|r|)
//   co-normality  Phi_N = |n_i - n_j|^2 phi(|r|)
//   co-circularity Phi_C = ((n_i + n_j) . r)^2 phi(|r|)
// force on i = -grad_{x_i} Phi; torque on i = -grad_theta Phi where n_i turns by a small rotation vector
// theta (n_i -> n_i + theta x n_i). The tests check every one against central finite differences.
// The thesis drops the phi' terms of the forces (§12.2.3); `drop_dphi` does the same (then the force is no
// longer the exact gradient). Sign note: the extracted thesis text has tau_N and tau_C with the opposite
// sign; the gradient gives tau_N = 2 phi (n_i x n_j) and tau_C = 2 c phi (r x n_i), c = (n_i + n_j) . r.
#pragma once

#include <cmath>

#include "surfeledit/core/particles/weighting.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

// One potential's value and its generalised forces on particle i.
struct PairTerm {
  double energy = 0.0;
  Vec3 force = Vec3::Zero();   // on i: -grad_{x_i}
  Vec3 torque = Vec3::Zero();  // on i: -grad over a small rotation of i
  double stiffness = 0.0;      // upper bound of the norm of the second derivative w.r.t. (x_i, theta_i)
                               // (used for the stable time step, see docs/particles.md)
};

// Stiffness bounds (docs/particles.md), shared by the per-term functions below and the fused pair kernel
// of compute_forces. Phi = (m . r)^2 phi with |m| <= m_norm: bounds of the x-x, theta-theta and x-theta
// blocks of its Hessian at distance rho = |r|.
inline double projection_stiffness(double m_norm, double rho, const WeightSample& w) {
  const double mr = m_norm * rho, phi = w.phi;
  const double dphi = std::abs(w.dphi), ddphi = std::abs(w.ddphi), dphi_r = std::abs(w.dphi_r);
  const double kx = 2.0 * m_norm * m_norm * phi + 4.0 * mr * m_norm * dphi + mr * mr * (ddphi + dphi_r);
  const double kt = (2.0 * rho * rho + 2.0 * mr * rho) * phi;
  const double kxt = (2.0 * m_norm * rho + 2.0 * mr) * phi + 2.0 * mr * rho * dphi;
  return kx + kt + kxt;
}
// Co-normality, b = |n_i - n_j|^2.
inline double conormality_stiffness(double b, const WeightSample& w) {
  return b * (std::abs(w.ddphi) + std::abs(w.dphi_r)) + 2.0 * w.phi + 2.0 * std::abs(w.dphi);
}

// `w` is the weight at |r|; `r` = x_j - x_i must be non-zero when w.dphi != 0.
PairTerm coplanarity(const Vec3& ni, const Vec3& r, const WeightSample& w, bool drop_dphi = false);
PairTerm conormality(const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w, bool drop_dphi = false);
PairTerm cocircularity(const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w, bool drop_dphi = false);

}  // namespace surfeledit
