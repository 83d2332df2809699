// The particle engine: neighbourhoods, forces, the stable-step check, integration, projection and local
// adaptive repulsion (thesis §12.2-12.3).
#include "surfeledit/core/particles/engine.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/particles/integrators.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

Values region_scale(const Points& particles, const Points& rigid, double gamma) {
  const Eigen::Index n = particles.rows();
  if (rigid.rows() == 0) return Values::Ones(n);
  KdTreeParams kp;
  kp.threads = 1;
  const KdTree tree(rigid, kp);
  Values d(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double dist2 = 0.0;
    tree.nearest(particles.row(i).transpose(), &dist2);
    d[i] = std::sqrt(dist2);
  }
  const double d_max = n > 0 ? d.maxCoeff() : 0.0;
  if (d_max == 0.0) return Values::Zero(n);
  return (d / d_max).array().pow(gamma).matrix();
}

ParticleEngine::ParticleEngine(ParticleState state, const Points& rigid, ParticleParams params)
    : state_(std::move(state)), rigid_(rigid), params_(params) {
  validate(params_);
  require_finite(state_.x, "positions");
  require_finite(rigid_, "rigid");
  const Eigen::Index n = state_.x.rows();
  if (static_cast<Eigen::Index>(state_.q.size()) != n || state_.v.rows() != n || state_.w.rows() != n ||
      state_.v_prev.rows() != n || state_.w_prev.rows() != n)
    throw Error(ErrorCode::InvalidArgument, "state", "inconsistent particle array sizes");
  scale_ = region_scale(state_.x, rigid_, params_.gamma);
  refresh_neighbours(true);
}

void ParticleEngine::set_surface(const Points& positions, const Points& normals) {
  require_finite(positions, "surface positions");
  surface_ = std::make_unique<SurfaceProjector>(positions, normals);
}

void ParticleEngine::set_constraint(Constraint constraint) {
  constraint_ = std::move(constraint);
  if (constraint_) apply_constraint();
  refresh_neighbours(true);
}

void ParticleEngine::apply_constraint() {
  for (Index i = 0; i < state_.size(); ++i) {
    Vec3 n = state_.normal(i);
    const Vec3 before = n;
    state_.x.row(i) = constraint_(state_.x.row(i).transpose(), &n).transpose();
    if (n != before && n.norm() > 0.0) {
      state_.q[i] = Eigen::Quaterniond::FromTwoVectors(before, n.normalized()) * state_.q[i];
      state_.q[i].normalize();
    }
  }
  evaluated_ = false;
}

void ParticleEngine::refresh_neighbours(bool force) {
  const double r = params_.weight.radius;
  switch (params_.neighbours) {
    case NeighbourMode::Cached:  // the one query by the grid: the same lists, built faster than by the k-d tree
      if (force) neighbours_grid(state_.x, r, params_.threads, grid_, nbrs_);
      break;
    case NeighbourMode::RecomputeGrid:  // exact every iteration; the Verlet list only saves grid queries
      if (force) verlet_.anchor.resize(0, 3);  // the particles may have changed (split / kill, constraint)
      neighbours_verlet(state_.x, r, params_.neighbour_skin * r, params_.threads, verlet_, nbrs_);
      break;
    case NeighbourMode::RecomputeKdTree: nbrs_ = neighbours_kdtree(state_.x, r, params_.threads); break;
  }
  evaluated_ = false;
}

void ParticleEngine::evaluate() {
  if (evaluated_) return;
  compute_forces(state_, nbrs_, params_, forces_);
  evaluated_ = true;
}

double ParticleEngine::energy() {
  evaluate();
  return forces_.energy;
}

double ParticleEngine::stable_dt() {
  evaluate();
  return stable_time_step(forces_, scale_, params_);
}

StepReport ParticleEngine::step() {
  if (params_.project_tangent && !surface_)
    throw Error(ErrorCode::Conflict, "project_tangent", "needs the original surface (set_surface)");
  StepReport report;
  evaluate();
  report.energy = forces_.energy;
  report.dt_stable = stable_time_step(forces_, scale_, params_);
  if (params_.dt > report.dt_stable) {
    const double needed = std::ceil(params_.dt / report.dt_stable);
    if (params_.policy == StepPolicy::Refuse || needed > params_.max_substeps)
      throw Error(ErrorCode::Conflict, "dt",
                  "dt = " + std::to_string(params_.dt) + " is above the stable time step " +
                      std::to_string(report.dt_stable) + " (" + std::to_string(needed) + " sub-steps needed)");
    report.substeps = static_cast<int>(needed);
  }
  const double h = params_.dt / report.substeps;
  for (int k = 0; k < report.substeps; ++k) {
    if (k > 0) {
      refresh_neighbours(false);
      evaluate();
    }
    integrate(state_, forces_, scale_, params_, h);
    if (params_.project_tangent) project_tangent();
    if (constraint_) apply_constraint();
    evaluated_ = false;
  }
  adapt(report);
  if (constraint_ && (report.split > 0 || report.killed > 0)) apply_constraint();
  refresh_neighbours(false);
  return report;
}

void ParticleEngine::project_tangent() {
  for (Index i = 0; i < state_.size(); ++i)
    state_.x.row(i) = surface_->onto_tangent_plane(state_.x.row(i).transpose()).transpose();
}

void ParticleEngine::project_mls(double h) {
  if (!surface_) throw Error(ErrorCode::Conflict, "surface", "project_mls needs the original surface (set_surface)");
  for (Index i = 0; i < state_.size(); ++i) {
    Vec3 n = state_.normal(i);
    state_.x.row(i) = surface_->onto_mls(state_.x.row(i).transpose(), h, &n).transpose();
    state_.q[i] = Eigen::Quaterniond::FromTwoVectors(state_.normal(i), n) * state_.q[i];
    state_.q[i].normalize();
  }
  evaluated_ = false;
}

// §12.3.7: kill where crowded, split where sparse (decided in index order on fresh counts), then relax the
// touched particles and their neighbours by a few steps of pure repulsion within their tangent planes.
void ParticleEngine::adapt(StepReport& report) {
  if (params_.split_below == 0 && params_.kill_above == 0) return;
  const double r = params_.weight.radius;
  Neighbourhood nb = neighbours_grid(state_.x, r, params_.threads);
  const Index n = state_.size();
  std::vector<Index> count(n);
  for (Index i = 0; i < n; ++i) count[i] = nb.count(i);
  std::vector<bool> keep(n, true), touched(n, false);
  for (Index i = 0; i < n && params_.kill_above > 0; ++i) {
    if (count[i] <= params_.kill_above) continue;
    keep[i] = false;
    ++report.killed;
    for (std::int64_t c = nb.offsets[i]; c < nb.offsets[i + 1]; ++c) {
      --count[nb.indices[c]];
      touched[nb.indices[c]] = true;
    }
  }
  for (Index i = 0; i < n && params_.split_below > 0; ++i) {
    if (!keep[i] || count[i] >= params_.split_below) continue;
    const Vec3 offset = 0.25 * r * state_.tangent(i);
    state_.append_copy(i, state_.x.row(i).transpose() + offset);
    state_.x.row(i) -= offset.transpose();
    scale_.conservativeResize(scale_.size() + 1);
    scale_[scale_.size() - 1] = scale_[i];
    keep.push_back(true);
    touched[i] = true;
    touched.push_back(true);
    ++report.split;
  }
  if (report.killed == 0 && report.split == 0) return;
  state_.keep(keep);
  compact(scale_, keep);
  compact(touched, keep);
  // Relaxation: gradient steps f / (2 k) of the repulsion alone, tangential part only.
  ParticleParams rp = params_;
  rp.alpha_planarity = rp.alpha_normality = rp.alpha_circularity = 0.0;
  if (rp.repulsion.kind == RepulsionKind::None) rp.repulsion.kind = RepulsionKind::Weight;
  rp.alpha_repulsion = 1.0;
  SystemForces f;
  for (int it = 0; it < params_.local_repulsion_steps; ++it) {
    nb = neighbours_grid(state_.x, r, params_.threads);
    compute_forces(state_, nb, rp, f);
    for (Index i = 0; i < state_.size(); ++i) {
      if (!touched[i] || f.stiffness[i] == 0.0) continue;
      const Vec3 ni = state_.normal(i);
      Vec3 move = f.force.row(i).transpose() / (2.0 * f.stiffness[i]);
      move -= move.dot(ni) * ni;
      state_.x.row(i) += move.transpose();
    }
  }
  refresh_neighbours(true);
}

}  // namespace surfeledit
