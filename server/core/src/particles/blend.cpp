// The blend region and one blend run of the particle system (thesis §12.3).
#include "surfeledit/core/particles/blend.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/particles/engine.hpp"
#include "../param_checks.hpp"

namespace surfeledit {

namespace {

constexpr Eigen::Index kBlendParallelFrom = 20000;  // particles

}  // namespace

void validate(const BlendParams& p) {
  using param_checks::require;
  using param_checks::require_finite;
  require(p.iterations >= 0 && p.iterations <= 100000, "iterations", p.iterations, "in [0, 100000]");
  require_finite(p.range_factor > 0.0, "range_factor", p.range_factor, "> 0");
  require_finite(p.neighbour_factor > 0.0, "neighbour_factor", p.neighbour_factor, "> 0");
  require_finite(p.dt > 0.0, "dt", p.dt, "> 0");
  require_finite(p.gamma >= 0.0, "gamma", p.gamma, ">= 0");
  require_finite(p.spring_r0 > 0.0, "spring_r0", p.spring_r0, "> 0");
  require_finite(p.mls_width > 0.0, "mls_width", p.mls_width, "> 0");
  require(p.split_below >= 1, "split_below", p.split_below, ">= 1");
  require(p.kill_above > p.split_below, "kill_above", p.kill_above, "> split_below");
  validate(blend_particle_params(p));
}

ParticleParams blend_particle_params(const BlendParams& p) {
  ParticleParams pp;
  pp.weight.kind = p.weight;
  pp.weight.radius = p.neighbour_factor;
  pp.repulsion.kind = p.repulsion;
  pp.repulsion.r0 = p.spring_r0;
  pp.repulsion.sigma = 0.3 * p.neighbour_factor;
  pp.dt = p.dt;
  pp.gamma = p.gamma;
  pp.only_grow = p.only_grow;
  pp.neighbours = p.neighbours;
  if (p.adaptive) {
    pp.split_below = p.split_below;
    pp.kill_above = p.kill_above;
    if (pp.neighbours == NeighbourMode::Cached) pp.neighbours = NeighbourMode::RecomputeGrid;
  }
  pp.max_substeps = 1024;
  pp.threads = p.threads;
  return pp;
}

BlendRegion blend_region(const SurfelModel& model, const IndexList& features, double range_factor) {
  BlendRegion out;
  if (features.empty()) return out;
  const double range = range_factor * model.radii().mean();
  Points seeds(static_cast<Eigen::Index>(features.size()), 3);
  for (std::size_t k = 0; k < features.size(); ++k) seeds.row(static_cast<Eigen::Index>(k)) = model.positions().row(features[k]);
  KdTreeParams kp;
  kp.threads = 1;
  const KdTree tree(model.positions(), kp);
  const RadiusResult hits = tree.radius(seeds, 2.0 * range);
  std::vector<std::uint8_t> label(static_cast<std::size_t>(model.size()), 0);  // 1 rigid, 2 blend
  const double r2 = range * range;
  for (std::size_t k = 0; k < hits.indices.size(); ++k) {
    const std::uint8_t l = hits.dist2[k] <= r2 ? 2 : 1;
    label[hits.indices[k]] = std::max(label[hits.indices[k]], l);
  }
  for (Index r : features) label[r] = 2;
  for (Index r = 0; r < model.size(); ++r) {
    if (label[r] == 2) out.rows.push_back(r);
    else if (label[r] == 1) out.rigid.push_back(r);
  }
  return out;
}

BlendRun run_blend(const Points& positions, const Points& normals, const Points& rigid, double mean_radius,
                   const BlendParams& params, const Points& rigid_normals) {
  validate(params);
  if (rigid_normals.rows() != 0 && rigid_normals.rows() != rigid.rows())
    throw Error(ErrorCode::InvalidArgument, "rigid_normals", "expected none or one per rigid point");
  param_checks::require_finite(mean_radius > 0.0, "mean_radius", mean_radius, "> 0");
  BlendRun out;
  if (positions.rows() == 0) return out;
  // Spacing units about the region's centroid.
  const Eigen::RowVector3d centre = positions.colwise().mean();
  const double unit = 1.0 / mean_radius;
  const Points x = (positions.rowwise() - centre) * unit;
  const Points rx = rigid.rows() > 0 ? Points((rigid.rowwise() - centre) * unit) : Points();
  ParticleParams pp = blend_particle_params(params);
  // Small systems run on one thread: the per-iteration work is too little to share (the result is the same).
  if (positions.rows() < kBlendParallelFrom) pp.threads = 1;
  ParticleEngine engine(ParticleState::from_surfels(x, normals), rx, pp);
  out.energy.resize(params.iterations);
  for (int it = 0; it < params.iterations; ++it) {
    const StepReport rep = engine.step();
    out.energy[it] = rep.energy;
    out.substeps += rep.substeps;
  }
  const ParticleState& s = engine.state();
  Points px = s.x, pn = s.normals();
  if (params.projection == ProjectionKind::Mls && px.rows() > 0) {
    // The surface the blend made: the particles, and the rigid region around them when its normals are known.
    const Eigen::Index nr = rigid_normals.rows();
    Points sx(px.rows() + nr, 3), sn(px.rows() + nr, 3);
    sx << px, rx.topRows(nr);
    sn << pn, rigid_normals;
    const SurfaceProjector surface(sx, sn);
    project_rows_mls(surface, params.mls_width, px, pn, pp.threads);
  }
  out.positions = (px * mean_radius).rowwise() + centre;
  out.normals = pn;
  out.origin = s.origin;
  return out;
}

}  // namespace surfeledit
