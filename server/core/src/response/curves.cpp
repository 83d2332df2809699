// Intersection curves: ordering the crease points and the 4-point refinement; see curves.hpp.
#include "surfeledit/core/response/curves.hpp"

#include <algorithm>
#include <cmath>

#include "detail.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {

void validate(const CurveParams& params) {
  using response_detail::require_at_least;
  require_at_least(params.refine_angle, 0.0, "refine_angle");
  require_at_least(params.weight, 0.0, "weight");
  require_at_least(params.min_angle, 0.0, "min_angle");
  require_at_least(params.merge_factor, 0.0, "merge_factor");
  require_at_least(params.max_edge_factor, 0.0, "max_edge_factor", true);
  if (params.neighbours < 2 || params.refine_passes < 0) {
    throw Error(ErrorCode::InvalidArgument, params.neighbours < 2 ? "neighbours" : "refine_passes",
                "neighbours must be >= 2 and refine_passes >= 0");
  }
}

Vec3 four_point(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double w) {
  return -w * a + (0.5 + w) * b + (0.5 + w) * c - w * d;
}

namespace {

// Angle u-v-w at v, radians (pi for a straight line).
double angle_at(const Vec3& u, const Vec3& v, const Vec3& w) {
  const Vec3 a = u - v, b = w - v;
  const double den = a.norm() * b.norm();
  return den > 0.0 ? std::acos(std::clamp(a.dot(b) / den, -1.0, 1.0)) : M_PI;
}

// Greedy merge of points closer than merge_factor x radius: cluster means and radii (of the first).
void merge_close(const Points& positions, const Values& radii, double factor, Points& out_pos,
                 Values& out_rad) {
  const Index n = static_cast<Index>(positions.rows());
  KdTreeParams tp;
  tp.threads = 1;
  const KdTree tree(positions, tp);
  std::vector<bool> taken(static_cast<std::size_t>(n), false);
  std::vector<Vec3> pos;
  std::vector<double> rad;
  IndexList hits;
  std::vector<double> dist2;
  for (Index i = 0; i < n; ++i) {
    if (taken[i]) continue;
    tree.radius(positions.row(i).transpose(), factor * radii[i], hits, dist2);
    Vec3 sum = Vec3::Zero();
    int count = 0;
    for (Index h : hits) {
      if (taken[h]) continue;
      taken[h] = true;
      sum += positions.row(h).transpose() - positions.row(i).transpose();  // relative: precision
      ++count;
    }
    pos.push_back(positions.row(i).transpose() + sum / std::max(count, 1));
    rad.push_back(radii[i]);
  }
  out_pos.resize(static_cast<Eigen::Index>(pos.size()), 3);
  out_rad.resize(static_cast<Eigen::Index>(rad.size()));
  for (std::size_t k = 0; k < pos.size(); ++k) {
    out_pos.row(static_cast<Eigen::Index>(k)) = pos[k].transpose();
    out_rad[static_cast<Eigen::Index>(k)] = rad[k];
  }
}

// Walks curves over merged points (see curves.hpp).
class Walker {
 public:
  Walker(const Points& pos, const Values& rad, const CurveParams& p)
      : pos_(pos), rad_(rad), p_(p), tree_(pos, tree_params()), used_(pos.rows(), false) {}

  std::vector<Curve> run() {
    std::vector<Curve> curves;
    for (Index seed = 0; seed < pos_.rows(); ++seed) {
      if (used_[seed]) continue;
      std::vector<Index> c{seed};
      used_[seed] = true;
      bool closed = extend(c);
      if (!closed && c.size() > 1) {
        std::reverse(c.begin(), c.end());
        closed = extend(c);
      }
      if (c.size() < p_.min_points) continue;
      Curve curve;
      curve.closed = closed;
      curve.points.resize(static_cast<Eigen::Index>(c.size()), 3);
      for (std::size_t k = 0; k < c.size(); ++k) curve.points.row(static_cast<Eigen::Index>(k)) = pos_.row(c[k]);
      curves.push_back(std::move(curve));
    }
    return curves;
  }

 private:
  static KdTreeParams tree_params() {
    KdTreeParams tp;
    tp.threads = 1;
    return tp;
  }
  Vec3 at(Index i) const { return pos_.row(i).transpose(); }

  // Appends vertices to the end of `c` while a next one is found; true when it closed.
  bool extend(std::vector<Index>& c) {
    IndexList nb;
    std::vector<double> dist2;
    for (;;) {
      const Index v = c.back();
      const double max_edge = p_.max_edge_factor * rad_[v];
      tree_.knn(at(v), p_.neighbours, nb, dist2);
      Index next = -1;
      for (std::size_t k = 0; k < nb.size(); ++k) {
        const Index w = nb[k];
        if (w == v) continue;
        if (dist2[k] > max_edge * max_edge) break;
        const bool closing = w == c.front() && c.size() >= 3;
        if (used_[w] && !closing) continue;
        if (c.size() >= 2 && angle_at(at(c[c.size() - 2]), at(v), at(w)) <= p_.min_angle) continue;
        next = w;
        break;
      }
      if (next < 0) return false;
      if (next == c.front()) return true;
      used_[next] = true;
      c.push_back(next);
    }
  }

  const Points& pos_;
  const Values& rad_;
  const CurveParams& p_;
  KdTree tree_;
  std::vector<bool> used_;
};

}  // namespace

Index refine_curve(Curve& curve, double refine_angle, double w) {
  const Eigen::Index k = curve.points.rows();
  if (k < 3) return 0;
  // Point i with the closed curve's wrap-around or the open curve's mirrored ends.
  auto p = [&](Eigen::Index i) -> Vec3 {
    if (curve.closed) return curve.points.row(((i % k) + k) % k).transpose();
    if (i < 0) return 2.0 * curve.points.row(0).transpose() - curve.points.row(1).transpose();
    if (i >= k) return 2.0 * curve.points.row(k - 1).transpose() - curve.points.row(k - 2).transpose();
    return curve.points.row(i).transpose();
  };
  // Bend at i: pi minus the angle (i-1)-i-(i+1).
  auto bend = [&](Eigen::Index i) { return M_PI - angle_at(p(i - 1), p(i), p(i + 1)); };
  const Eigen::Index edges = curve.closed ? k : k - 1;
  std::vector<Vec3> out;
  out.reserve(static_cast<std::size_t>(2 * k));
  Index added = 0;
  for (Eigen::Index i = 0; i < k; ++i) {
    out.push_back(p(i));
    if (i < edges && std::max(bend(i), bend(i + 1)) > refine_angle) {
      out.push_back(four_point(p(i - 1), p(i), p(i + 1), p(i + 2), w));
      ++added;
    }
  }
  if (added == 0) return 0;
  curve.points.resize(static_cast<Eigen::Index>(out.size()), 3);
  for (std::size_t j = 0; j < out.size(); ++j) curve.points.row(static_cast<Eigen::Index>(j)) = out[j].transpose();
  return added;
}

std::vector<Curve> intersection_curves(const Points& positions, const Values& radii,
                                       const CurveParams& params) {
  validate(params);
  if (radii.size() != positions.rows()) {
    throw Error(ErrorCode::InvalidArgument, "radii",
                "has " + std::to_string(radii.size()) + " values, expected " +
                    std::to_string(positions.rows()) + " (one per position)");
  }
  require_finite(positions, "positions");
  require_finite(radii, "radii");
  if (positions.rows() == 0) return {};
  Points pos;
  Values rad;
  merge_close(positions, radii, params.merge_factor, pos, rad);
  std::vector<Curve> curves = Walker(pos, rad, params).run();
  for (Curve& c : curves)
    for (int pass = 0; pass < params.refine_passes; ++pass)
      if (refine_curve(c, params.refine_angle, params.weight) == 0) break;
  return curves;
}

}  // namespace surfeledit
