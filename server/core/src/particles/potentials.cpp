// Co-planarity, co-normality and co-circularity for one ordered pair: value, exact force and torque on i,
// and a bound on the local stiffness (thesis §12.2.2-12.2.3). With r = x_j - x_i, -grad_{x_i} = +grad_r;
// a rotation theta of i changes n_i by theta x n_i, so the torque is (dPhi/dn_i) x n_i.
#include "surfeledit/core/particles/potentials.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace surfeledit {

namespace {

// Phi = a^2 phi with a = m . r, where only n_i (one unit term of m) turns with theta_i; `m_norm` bounds |m|.
// Force 2 a phi m + a^2 phi'/|r| r; torque 2 a phi (r x n_i).
PairTerm squared_projection(const Vec3& m, double m_norm, const Vec3& ni, const Vec3& r, const WeightSample& w,
                            bool drop_dphi) {
  PairTerm t;
  const double a = m.dot(r);
  t.energy = a * a * w.phi;
  t.force = 2.0 * a * w.phi * m;
  if (!drop_dphi) t.force += a * a * w.dphi_r * r;
  t.torque = 2.0 * a * w.phi * r.cross(ni);
  t.stiffness = projection_stiffness(m_norm, r.norm(), w);  // |a| <= m_norm rho
  return t;
}

}  // namespace

PairTerm coplanarity(const Vec3& ni, const Vec3& r, const WeightSample& w, bool drop_dphi) {
  return squared_projection(ni, 1.0, ni, r, w, drop_dphi);
}

PairTerm cocircularity(const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w, bool drop_dphi) {
  return squared_projection(ni + nj, 2.0, ni, r, w, drop_dphi);
}

PairTerm conormality(const Vec3& ni, const Vec3& nj, const Vec3& r, const WeightSample& w, bool drop_dphi) {
  PairTerm t;
  const double b = (ni - nj).squaredNorm();
  t.energy = b * w.phi;
  if (!drop_dphi) t.force = b * w.dphi_r * r;
  t.torque = 2.0 * w.phi * ni.cross(nj);
  t.stiffness = conormality_stiffness(b, w);
  return t;
}

}  // namespace surfeledit
