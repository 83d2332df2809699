// Sharp crease: feature surfels onto the intersection curve, clip lines, gap copies; see crease.hpp.
#include "surfeledit/core/response/crease.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "detail.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {

void validate(const CreaseParams& params) {
  response_detail::require_at_least(params.gap_factor, 0.0, "gap_factor", true);
  response_detail::require_at_least(params.max_move_factor, 0.0, "max_move_factor", true);
  response_detail::require_at_least(params.min_angle, 0.0, "min_angle", true);
}

bool crease_point(const Vec3& p_i, const Vec3& n_i, const Vec3& p_j, const Vec3& n_j, double min_angle,
                  Vec3& x) {
  const Vec3 c = n_i.cross(n_j);
  if (!(c.norm() > std::sin(std::min(min_angle, M_PI / 2)))) return false;
  // Solved relative to the midpoint m (precision far from the origin): x = m + delta with
  // n_i . delta = n_i . (p_i - m), n_j . delta = n_j . (p_j - m), c . delta = 0.
  const Vec3 m = 0.5 * (p_i + p_j);
  Mat3 a;
  a.row(0) = n_i.transpose();
  a.row(1) = n_j.transpose();
  a.row(2) = c.normalized().transpose();
  const Vec3 b(n_i.dot(p_i - m), n_j.dot(p_j - m), 0.0);
  x = m + a.partialPivLu().solve(b);
  return x.allFinite();
}

namespace {

// One moved surfel and where it went.
struct Move {
  Index row;
  Vec3 x;    // new position (on the curve)
  Vec3 dir;  // clip direction
};

// Moves of the rows of one side, each paired with its nearest feature of the other side.
void moves_of(const SurfelModel& model, const IndexList& side, const KdTree& other,
              const CreaseParams& params, std::vector<Move>& out) {
  const Points& pos = model.positions();
  const Points& nrm = model.normals();
  for (Index i : side) {
    const Index j = other.nearest(pos.row(i).transpose());
    if (j < 0) return;
    const Vec3 p_i = pos.row(i).transpose(), n_i = nrm.row(i).transpose();
    const Vec3 n_j = nrm.row(j).transpose();
    Vec3 x;
    if (!crease_point(p_i, n_i, pos.row(j).transpose(), n_j, params.min_angle, x)) continue;
    const double reach = params.max_move_factor * model.radii()[i];
    if ((x - p_i).squaredNorm() > reach * reach) continue;
    // n_i x dir = the other side's normal projected into i's plane: the kept half faces away from it.
    out.push_back({i, x, n_j.cross(n_i).normalized()});
  }
}

// Appends the gap-covering copy of Eq. 11.1 for a surfel moved from `p` by `d` (row `r` of `model`).
void add_gap_copy(const SurfelModel& model, Index r, const Vec3& d, SurfelArrays& out, Index k) {
  const Vec3 p = model.positions().row(r).transpose();
  const Vec3 n = model.normals().row(r).transpose();
  double radius = model.radii()[r];
  Vec3 centre;
  if (model.has_tangents()) {
    const Vec3 tu = model.tangent_u().row(r).transpose(), tv = model.tangent_v().row(r).transpose();
    const bool along_v = std::abs(d.dot(tv.normalized())) > std::abs(d.dot(tu.normalized()));
    const Vec3 u = along_v ? tv : tu, v = along_v ? tu : tv;  // u: the axis the move projects on most
    const double lu = u.norm(), du = d.dot(u / lu);
    centre = p - (du < 0.0 ? -0.5 : 0.5) * (lu - std::abs(du)) * (u / lu);
    const Vec3 u_new = u * (0.5 * (lu + std::abs(du)) / lu);
    out.tangent_u.row(k) = (along_v ? v : u_new).transpose();
    out.tangent_v.row(k) = (along_v ? u_new : v).transpose();
    radius = std::max(u_new.norm(), v.norm());
  } else {
    const Vec3 t = d - d.dot(n) * n;  // the move's tangential part
    const double dt = t.norm();
    centre = p - 0.5 * (radius - dt) * (dt > 0.0 ? Vec3(t / dt) : Vec3::Zero());
    radius = 0.5 * (radius + dt);
  }
  out.positions.row(k) = centre.transpose();
  out.normals.row(k) = n.transpose();
  out.radii[k] = radius;
  if (model.has_colors()) out.colors.row(k) = model.colors().row(r);
}

}  // namespace

CreaseResult crease(const SurfelModel& model, const IdList& features_a, const IdList& features_b,
                    const CreaseParams& params) {
  validate(params);
  const IndexList rows_a = model.rows_of(features_a, "features_a");
  const IndexList rows_b = model.rows_of(features_b, "features_b");
  KdTreeParams tp;
  tp.threads = 1;
  const KdTree tree_a(model.positions(), rows_a, tp), tree_b(model.positions(), rows_b, tp);
  std::vector<Move> moves;
  moves_of(model, rows_a, tree_b, params, moves);
  moves_of(model, rows_b, tree_a, params, moves);
  std::sort(moves.begin(), moves.end(), [](const Move& l, const Move& r) { return l.row < r.row; });

  CreaseResult out;
  const auto n = static_cast<Eigen::Index>(moves.size());
  out.positions.resize(n, 3);
  out.clip_dirs.resize(n, 3);
  std::vector<Index> gaps;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Move& m = moves[static_cast<std::size_t>(k)];
    out.moved.push_back(model.id_of(m.row));
    out.positions.row(k) = m.x.transpose();
    out.clip_dirs.row(k) = m.dir.transpose();
    const double gap = params.gap_factor * model.radii()[m.row];
    if ((m.x - model.positions().row(m.row).transpose()).squaredNorm() > gap * gap) gaps.push_back(k);
  }
  out.clip_points = out.positions;

  const auto g = static_cast<Eigen::Index>(gaps.size());
  SurfelArrays& ins = out.inserted;
  ins.positions.resize(g, 3);
  ins.normals.resize(g, 3);
  ins.radii.resize(g);
  if (model.has_tangents()) ins.tangent_u.resize(g, 3), ins.tangent_v.resize(g, 3);
  if (model.has_colors()) ins.colors.resize(g, 3);
  for (Eigen::Index k = 0; k < g; ++k) {
    const Move& m = moves[static_cast<std::size_t>(gaps[k])];
    add_gap_copy(model, m.row, m.x - model.positions().row(m.row).transpose(), ins, static_cast<Index>(k));
    out.inserted_parents.push_back(model.id_of(m.row));
  }
  return out;
}

IdList apply_crease(SurfelModel& model, const CreaseResult& crease) {
  const IndexList rows = model.rows_of(crease.moved, "moved");
  if (crease.positions.rows() != static_cast<Eigen::Index>(rows.size())) {
    throw Error(ErrorCode::InvalidArgument, "positions",
                "has " + std::to_string(crease.positions.rows()) + " rows, expected " +
                    std::to_string(rows.size()) + " (one per moved id)");
  }
  require_finite(crease.positions, "positions");
  validate_arrays(crease.inserted, model.has_tangents(), model.has_colors());
  model.set_clips(crease.moved, crease.clip_points, crease.clip_dirs);
  for (std::size_t k = 0; k < rows.size(); ++k)
    model.arrays().positions.row(rows[k]) = crease.positions.row(static_cast<Eigen::Index>(k));
  return model.insert(crease.inserted);
}

}  // namespace surfeledit
