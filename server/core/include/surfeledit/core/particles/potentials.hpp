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

// `w` is the weight at |r|; `r` = x_j - x_i must be non-zero when w.dphi != 0.
PairTerm coplanarity(const Vec3& ni, const Vec3& r, const WeightSample& w, bool drop_dphi = false);
PairTerm conormality(const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w, bool drop_dphi = false);
PairTerm cocircularity(const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w, bool drop_dphi = false);

}  // namespace surfeledit
