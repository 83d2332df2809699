// Particle state: construction from surfels, copies and removal.
#include "surfeledit/core/particles/state.hpp"

#include "surfeledit/core/util.hpp"

namespace surfeledit {

Points ParticleState::normals() const {
  Points n(size(), 3);
  for (Index i = 0; i < size(); ++i) n.row(i) = normal(i).transpose();
  return n;
}

ParticleState ParticleState::from_surfels(const Points& positions, const Points& normals) {
  require_finite(positions, "positions");
  require_finite(normals, "normals");
  if (normals.rows() != positions.rows())
    throw Error(ErrorCode::InvalidArgument, "normals", "expected one normal per position");
  ParticleState s;
  const Index n = static_cast<Index>(positions.rows());
  s.x = positions;
  s.q.resize(n);
  for (Index i = 0; i < n; ++i) {
    const Vec3 ni = normals.row(i).transpose();
    if (ni.norm() == 0.0) throw Error(ErrorCode::InvalidArgument, "normals", "zero normal at row " + std::to_string(i));
    s.q[i] = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), ni.normalized()).normalized();
  }
  s.v = s.w = s.v_prev = s.w_prev = Points::Zero(n, 3);
  s.origin.resize(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) s.origin[static_cast<std::size_t>(i)] = i;
  return s;
}

void ParticleState::append_copy(Index i, const Vec3& at) {
  const Index n = size();
  for (Points* a : {&x, &v, &w, &v_prev, &w_prev}) a->conservativeResize(n + 1, 3);
  x.row(n) = at.transpose();
  v.row(n).setZero();
  w.row(n).setZero();
  v_prev.row(n).setZero();
  w_prev.row(n).setZero();
  q.push_back(q[i]);
  if (origin.size() == static_cast<std::size_t>(n)) {
    const std::int64_t t = origin[static_cast<std::size_t>(i)];
    origin.push_back(t >= 0 ? -1 - t : t);
  }
}

void ParticleState::keep(const std::vector<bool>& flags) {
  for (Points* a : {&x, &v, &w, &v_prev, &w_prev}) compact(*a, flags);
  compact(q, flags);
  if (origin.size() == flags.size()) compact(origin, flags);
}

}  // namespace surfeledit
