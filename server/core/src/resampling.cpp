// Dynamic resampling (docs/algorithms.md §1): split surfels whose deformed tangent ellipse is stretched
// beyond a threshold, along the direction of greatest stretch.
#include "surfeledit/core/resampling.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace surfeledit {

void validate(const ResampleParams& params) {
  if (!std::isfinite(params.split_threshold) || !(params.split_threshold > 1.0)) {
    std::ostringstream msg;
    msg << "must be finite and > 1, got " << params.split_threshold;
    throw Error(ErrorCode::InvalidArgument, "split_threshold", msg.str());
  }
}

void make_tangent_frames(const Points& normals, const Values& radii, Points& tangent_u, Points& tangent_v) {
  const Eigen::Index n = normals.rows();
  if (radii.size() != n) {
    throw Error(ErrorCode::InvalidArgument, "radii",
                "has " + std::to_string(radii.size()) + " entries but normals have " + std::to_string(n) + " rows");
  }
  tangent_u.resize(n, 3);
  tangent_v.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3 nrm = normals.row(i).transpose().normalized();
    // The coordinate axis least aligned with the normal seeds u (deterministic, never parallel).
    Eigen::Index axis = 0;
    nrm.cwiseAbs().minCoeff(&axis);
    const Vec3 u = nrm.cross(Vec3::Unit(axis)).normalized();
    const Vec3 v = nrm.cross(u);
    tangent_u.row(i) = (radii[i] * u).transpose();
    tangent_v.row(i) = (radii[i] * v).transpose();
  }
}

SplitPlan plan_splits(const SurfelArrays& model, const IndexList& candidates, const Values& rest_radius,
                      const ResampleParams& params) {
  validate(params);
  const Eigen::Index n = model.positions.rows();
  if (model.tangent_u.rows() != n || model.tangent_v.rows() != n) {
    throw Error(ErrorCode::InvalidArgument, "tangent_u", "resampling needs tangent axes for every surfel");
  }
  if (rest_radius.size() != n) {
    throw Error(ErrorCode::InvalidArgument, "rest_radius",
                "has " + std::to_string(rest_radius.size()) + " entries but the model has " + std::to_string(n));
  }
  const bool colors = model.colors.rows() == n;
  SplitPlan plan;
  struct Child {
    Vec3 offset, u, v;
    double radius;
  };
  std::vector<Child> children;
  Index prev = -1;
  for (Index r : candidates) {
    if (r <= prev || r >= n) {
      throw Error(ErrorCode::InvalidArgument, "candidates", "row " + std::to_string(r) + " is out of range or not ascending");
    }
    prev = r;
    const Vec3 u = model.tangent_u.row(r).transpose(), v = model.tangent_v.row(r).transpose();
    // First fundamental form G = M^T M with M = [u v]; its eigenvectors w1 (largest), w2 map to the
    // ellipse's orthogonal semi-axes M w1 (length sqrt(lambda_max)) and M w2.
    const double guu = u.dot(u), guv = u.dot(v), gvv = v.dot(v);
    const double mean = 0.5 * (guu + gvv), diff = 0.5 * (guu - gvv);
    const double root = std::sqrt(diff * diff + guv * guv);
    const double lmax = mean + root, lmin = std::max(0.0, mean - root);
    const double a_e = std::sqrt(lmax);
    if (!(a_e > params.split_threshold * rest_radius[r])) continue;
    // Unit eigenvector of lambda_max: (guv, lmax - guu) or (lmax - gvv, guv), whichever is longer.
    Eigen::Vector2d w1(guv, lmax - guu);
    const Eigen::Vector2d alt(lmax - gvv, guv);
    if (alt.squaredNorm() > w1.squaredNorm()) w1 = alt;
    if (!(w1.squaredNorm() > 0.0)) w1 = Eigen::Vector2d(1.0, 0.0);  // isotropic: any direction
    w1.normalize();
    const Eigen::Vector2d w2(-w1.y(), w1.x());
    const Vec3 axis_e = w1.x() * u + w1.y() * v;  // length a_e, direction e
    const Vec3 axis_f = w2.x() * u + w2.y() * v;  // length sqrt(lambda_min)
    const double b = std::sqrt(lmin);
    Child c;
    c.offset = 0.5 * axis_e;  // (a_e / 2) e
    c.u = 0.5 * axis_e;
    c.v = axis_f;
    c.radius = std::max(0.5 * a_e, b);
    plan.parents.push_back(r);
    children.push_back(c);
  }
  const Eigen::Index k = static_cast<Eigen::Index>(plan.parents.size());
  for (SurfelArrays* out : {&plan.a, &plan.b}) {
    out->positions.resize(k, 3);
    out->normals.resize(k, 3);
    out->radii.resize(k);
    out->tangent_u.resize(k, 3);
    out->tangent_v.resize(k, 3);
    if (colors) out->colors.resize(k, 3);
  }
  for (Eigen::Index j = 0; j < k; ++j) {
    const Index r = plan.parents[static_cast<std::size_t>(j)];
    const Child& c = children[static_cast<std::size_t>(j)];
    const Vec3 p = model.positions.row(r).transpose();
    for (int side = 0; side < 2; ++side) {
      SurfelArrays& out = side == 0 ? plan.a : plan.b;
      out.positions.row(j) = (p + (side == 0 ? -1.0 : 1.0) * c.offset).transpose();
      out.normals.row(j) = model.normals.row(r);
      out.radii[j] = c.radius;
      out.tangent_u.row(j) = c.u.transpose();
      out.tangent_v.row(j) = c.v.transpose();
      if (colors) out.colors.row(j) = model.colors.row(r);
    }
  }
  return plan;
}

}  // namespace surfeledit
