// OBB fit by PCA (thesis §8.2.1, Eq. 8.6) and growth operations.
#include "surfeledit/core/bvh/obb.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <array>
#include <limits>
#include <cmath>

namespace surfeledit::bvh {

namespace {

// Relative padding added by the fit so that the surfels it was fit to pass contains() after rounding.
double pad_for(const Vec3& center, const Vec3& ext) {
  return 1e-12 * (1.0 + center.cwiseAbs().maxCoeff() + ext.cwiseAbs().maxCoeff());
}
double tolerance_for(const Obb& b) {
  return 1e-9 * (1.0 + b.center.cwiseAbs().maxCoeff() + b.ext.cwiseAbs().maxCoeff());
}

// Sets centre and half extents from per-axis bounds in the box frame (lo, hi along the rows of axes),
// where the frame's origin is `origin`.
void set_from_local_bounds(Obb& b, const Vec3& origin, const Vec3& lo, const Vec3& hi) {
  const Vec3 mid = 0.5 * (lo + hi);
  b.center = origin + b.axes.transpose() * mid;
  b.ext = 0.5 * (hi - lo);
  b.ext.array() += pad_for(b.center, b.ext);
}

}  // namespace

Obb Obb::fit(const Points& positions, const Values& radii, const Index* rows, std::size_t n) {
  Obb b;
  Vec3 mean = Vec3::Zero();
  std::size_t live = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (rows[k] < 0) continue;
    mean += positions.row(rows[k]).transpose();
    ++live;
  }
  if (live == 0) return b;
  mean /= double(live);
  // Covariance C_jk = 1/n sum (p_i - mean)_j (p_i - mean)_k (Eq. 8.6).
  Mat3 cov = Mat3::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    if (rows[k] < 0) continue;
    const Vec3 d = positions.row(rows[k]).transpose() - mean;
    cov.noalias() += d * d.transpose();
  }
  cov /= double(live);
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(cov);
  // Eigenvalues ascending: row 0 = largest variance (the split axis), row 2 = smallest.
  Mat3 axes;
  axes.row(0) = eig.eigenvectors().col(2).transpose().normalized();
  axes.row(1) = eig.eigenvectors().col(1).transpose();
  axes.row(1) = (axes.row(1) - axes.row(1).dot(axes.row(0)) * axes.row(0)).normalized();
  axes.row(2) = axes.row(0).cross(axes.row(1));
  if (!axes.allFinite() || std::abs(axes.determinant() - 1.0) > 1e-6) axes = Mat3::Identity();
  b.axes = axes;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (std::size_t k = 0; k < n; ++k) {
    const Index i = rows[k];
    if (i < 0) continue;
    const Vec3 local = axes * (positions.row(i).transpose() - mean);
    const double r = radius_of(radii, i);
    lo = lo.cwiseMin((local.array() - r).matrix());
    hi = hi.cwiseMax((local.array() + r).matrix());
  }
  set_from_local_bounds(b, mean, lo, hi);
  return b;
}

void Obb::expand(const Vec3& p, double r) {
  if (empty()) {
    center = p;
    ext = Vec3::Constant(r);
    ext.array() += pad_for(center, ext);
    return;
  }
  const Vec3 local = to_local(p);
  const Vec3 lo = (-ext).cwiseMin((local.array() - r).matrix());
  const Vec3 hi = ext.cwiseMax((local.array() + r).matrix());
  if (lo == -ext && hi == ext) return;
  set_from_local_bounds(*this, center, lo, hi);
}

void Obb::enclose(const Obb& child) {
  if (child.empty()) return;
  if (empty()) {
    *this = child;
    return;
  }
  Vec3 lo = -ext, hi = ext;
  bool grew = false;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 c_local;
    for (int d = 0; d < 3; ++d) c_local[d] = (corner >> d & 1) ? child.ext[d] : -child.ext[d];
    const Vec3 world = child.center + child.axes.transpose() * c_local;
    const Vec3 local = to_local(world);
    if ((local.array() < lo.array()).any() || (local.array() > hi.array()).any()) grew = true;
    lo = lo.cwiseMin(local);
    hi = hi.cwiseMax(local);
  }
  if (grew) set_from_local_bounds(*this, center, lo, hi);
}

bool Obb::contains(const Vec3& p, double r) const {
  if (empty()) return false;
  const Vec3 local = to_local(p);
  return (local.array().abs() + r <= ext.array() + tolerance_for(*this)).all();
}

bool Obb::contains(const Obb& child) const {
  if (child.empty()) return true;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 c_local;
    for (int d = 0; d < 3; ++d) c_local[d] = (corner >> d & 1) ? child.ext[d] : -child.ext[d];
    if (!contains(child.center + child.axes.transpose() * c_local, 0.0)) return false;
  }
  return true;
}

}  // namespace surfeledit::bvh
