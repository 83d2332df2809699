// Hole detection (angular gaps, loops) and filling (seeding on a fitted quadric, particle diffusion).
#include "surfeledit/core/holes.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/particles/engine.hpp"
#include "surfeledit/core/util.hpp"
#include "param_checks.hpp"
#include "union_find.hpp"

namespace surfeledit {

namespace {

// Two unit vectors spanning the plane normal to unit n.
void basis(const Vec3& n, Vec3& e1, Vec3& e2) {
  e1 = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
  e2 = n.cross(e1);
}

// Largest gap (radians) between the directions `angles` (sorted in place), wrapping around.
double largest_gap(std::vector<double>& angles) {
  if (angles.empty()) return 2.0 * M_PI;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2.0 * M_PI - angles.back();
  for (std::size_t k = 1; k < angles.size(); ++k) gap = std::max(gap, angles[k] - angles[k - 1]);
  return gap;
}

// z = c0 u^2 + c1 u v + c2 v^2 + c3 u + c4 v + c5 over the plane (centre, e1, e2, n).
struct HeightField {
  Vec3 centre, e1, e2, n;
  Eigen::Matrix<double, 6, 1> c = Eigen::Matrix<double, 6, 1>::Zero();
  Vec3 at(double u, double v, Vec3* normal) const {
    const double z = c[0] * u * u + c[1] * u * v + c[2] * v * v + c[3] * u + c[4] * v + c[5];
    const double zu = 2 * c[0] * u + c[1] * v + c[3], zv = c[1] * u + 2 * c[2] * v + c[4];
    if (normal) *normal = (n - zu * e1 - zv * e2).normalized();
    return centre + u * e1 + v * e2 + z * n;
  }
  // x moved along n onto the height field (its plane coordinates kept).
  Vec3 project(const Vec3& x, Vec3* normal) const {
    const Vec3 d = x - centre;
    return at(d.dot(e1), d.dot(e2), normal);
  }
};

HeightField fit_height_field(const SurfelModel& model, const IndexList& ring, const Vec3& centre) {
  HeightField f;
  f.centre = centre;
  Vec3 n = Vec3::Zero();
  for (Index r : ring) n += model.normals().row(r).transpose();
  f.n = n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3::UnitZ();
  basis(f.n, f.e1, f.e2);
  const Eigen::Index m = static_cast<Eigen::Index>(ring.size());
  if (m < 6) return f;
  Eigen::MatrixXd a(m, 6);
  Eigen::VectorXd b(m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Vec3 d = model.positions().row(ring[k]).transpose() - centre;
    const double u = d.dot(f.e1), v = d.dot(f.e2);
    a.row(k) << u * u, u * v, v * v, u, v, 1.0;
    b[k] = d.dot(f.n);
  }
  f.c = a.colPivHouseholderQr().solve(b);
  if (!f.c.allFinite()) f.c.setZero();
  return f;
}

}  // namespace

void validate(const HoleParams& p) {
  using param_checks::require_finite;
  require_finite(p.max_diameter > 0.0, "max_diameter", p.max_diameter, "a finite number > 0");
  require_finite(p.iterations >= 0 && p.iterations <= 10000, "iterations", p.iterations, "in [0, 10000]");
  require_finite(p.neighbours >= 4 && p.neighbours <= 64, "neighbours", p.neighbours, "in [4, 64]");
  require_finite(p.gap_angle > 0.0 && p.gap_angle < 2.0 * M_PI, "gap_angle", p.gap_angle, "in (0, 2 pi)");
  require_finite(p.link_factor > 0.0, "link_factor", p.link_factor, "> 0");
  require_finite(p.min_loop >= 3, "min_loop", p.min_loop, ">= 3");
  require_finite(p.ring_factor > 0.0, "ring_factor", p.ring_factor, "> 0");
  require_finite(p.mls_width > 0.0, "mls_width", p.mls_width, "> 0");
}

IndexList boundary_rows(const SurfelModel& model, const HoleParams& params) {
  const Index n = model.size();
  KdTreeParams kp;
  kp.threads = params.threads;
  const KdTree tree(model.positions(), kp);
  std::vector<std::uint8_t> flag(static_cast<std::size_t>(n), 0);
#pragma omp parallel for schedule(static) num_threads(resolve_threads(params.threads))
  for (Index i = 0; i < n; ++i) {
    IndexList idx;
    std::vector<double> d2;
    const Vec3 p = model.positions().row(i).transpose(), ni = model.normals().row(i).transpose();
    tree.knn(p, params.neighbours + 1, idx, d2);
    Vec3 e1, e2;
    basis(ni, e1, e2);
    std::vector<double> angles;
    for (Index j : idx) {
      if (j == i) continue;
      const Vec3 d = model.positions().row(j).transpose() - p;
      const double u = d.dot(e1), v = d.dot(e2);
      if (u != 0.0 || v != 0.0) angles.push_back(std::atan2(v, u));
    }
    flag[i] = largest_gap(angles) > params.gap_angle ? 1 : 0;
  }
  IndexList out;
  for (Index i = 0; i < n; ++i)
    if (flag[i]) out.push_back(i);
  return out;
}

std::vector<Hole> group_loops(const SurfelModel& model, const IndexList& boundary, const HoleParams& params) {
  std::vector<Hole> out;
  if (boundary.empty()) return out;
  const Index m = static_cast<Index>(boundary.size());
  Points p(m, 3);
  double mean_r = 0.0;
  for (Index k = 0; k < m; ++k) {
    p.row(k) = model.positions().row(boundary[k]);
    mean_r += model.radii()[boundary[k]];
  }
  mean_r /= static_cast<double>(m);
  KdTreeParams kp;
  kp.threads = 1;
  const KdTree tree(p, kp);
  const RadiusResult hits = tree.radius(p, params.link_factor * mean_r);
  std::vector<Index> parent(static_cast<std::size_t>(m));
  std::iota(parent.begin(), parent.end(), Index{0});
  for (Index k = 0; k < m; ++k)
    for (std::int64_t e = hits.offsets[k]; e < hits.offsets[k + 1]; ++e) {
      const int a = union_find::find_root(parent, k), b = union_find::find_root(parent, hits.indices[e]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  std::vector<IndexList> groups(static_cast<std::size_t>(m));
  for (Index k = 0; k < m; ++k) groups[union_find::find_root(parent, k)].push_back(k);
  for (const IndexList& g : groups) {
    if (static_cast<int>(g.size()) < params.min_loop) continue;
    Hole h;
    double d2max = 0.0;
    if (g.size() <= 4000) {
      for (std::size_t a = 0; a < g.size(); ++a)
        for (std::size_t b = a + 1; b < g.size(); ++b) d2max = std::max(d2max, (p.row(g[a]) - p.row(g[b])).squaredNorm());
    } else {  // two sweeps from the first point: a lower bound at least half the diameter
      Index far = g[0];
      for (int sweep = 0; sweep < 2; ++sweep) {
        const Index from = far;
        for (Index k : g) {
          const double d2 = (p.row(k) - p.row(from)).squaredNorm();
          if (d2 > d2max) d2max = d2, far = k;
        }
      }
    }
    h.diameter = std::sqrt(d2max);
    for (Index k : g) h.boundary.push_back(boundary[k]);
    out.push_back(std::move(h));
  }
  return out;
}

HoleFilling fill_hole(const SurfelModel& model, const Hole& hole, const HoleParams& params) {
  HoleFilling out;
  const IndexList& loop = hole.boundary;
  if (loop.size() < 3) return out;
  Vec3 centre = Vec3::Zero();
  double h = 0.0;
  for (Index r : loop) {
    centre += model.positions().row(r).transpose();
    h += model.radii()[r];
  }
  centre /= static_cast<double>(loop.size());
  h /= static_cast<double>(loop.size());
  KdTreeParams kp;
  kp.threads = 1;
  const KdTree tree(model.positions(), kp);
  // The ring: surfels near the loop, for the height field.
  Points lp(static_cast<Eigen::Index>(loop.size()), 3);
  for (std::size_t k = 0; k < loop.size(); ++k) lp.row(static_cast<Eigen::Index>(k)) = model.positions().row(loop[k]);
  const RadiusResult near = tree.radius(lp, params.ring_factor * h);
  IndexList ring(near.indices.begin(), near.indices.end());
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  const HeightField field = fit_height_field(model, ring, centre);
  // Seeds: a hexagonal grid of step h over the loop's plane, inside the loop (the loop surrounds it: no
  // gap of pi among the directions to its surfels) and not yet covered (no surfel within 0.75 h).
  double extent = 0.0;
  std::vector<std::pair<double, double>> uv(loop.size());
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec3 d = lp.row(static_cast<Eigen::Index>(k)).transpose() - centre;
    uv[k] = {d.dot(field.e1), d.dot(field.e2)};
    extent = std::max(extent, std::hypot(uv[k].first, uv[k].second));
  }
  std::vector<Vec3> seeds, seed_normals;
  const double row_step = h * std::sqrt(3.0) / 2.0;
  const int rows = static_cast<int>(std::ceil(extent / row_step));
  const int cols = static_cast<int>(std::ceil(extent / h)) + 1;
  for (int a = -rows; a <= rows; ++a)
    for (int b = -cols; b <= cols; ++b) {
      const double u = (b + 0.5 * (a & 1)) * h, v = a * row_step;
      if (std::hypot(u, v) > extent) continue;
      std::vector<double> angles;
      angles.reserve(uv.size());
      for (const auto& [lu, lv] : uv) angles.push_back(std::atan2(lv - v, lu - u));
      if (largest_gap(angles) >= M_PI) continue;
      Vec3 n;
      const Vec3 x = field.at(u, v, &n);
      double d2 = 0.0;
      tree.nearest(x, &d2);
      if (d2 < 0.5625 * h * h) continue;
      seeds.push_back(x);
      seed_normals.push_back(n);
    }
  if (seeds.empty()) return out;
  Points sx(static_cast<Eigen::Index>(seeds.size()), 3), sn(sx.rows(), 3);
  for (std::size_t k = 0; k < seeds.size(); ++k) {
    sx.row(static_cast<Eigen::Index>(k)) = seeds[k].transpose();
    sn.row(static_cast<Eigen::Index>(k)) = seed_normals[k].transpose();
  }
  // Diffusion in spacing units (h = 1): repulsion and local adaptive split / kill, kept on the height field;
  // the ring anchors the particles next to it (region scaling).
  if (params.iterations > 0 && sx.rows() > 1) {
    ParticleParams pp;
    pp.weight.radius = 2.0;
    pp.alpha_planarity = pp.alpha_normality = pp.alpha_circularity = 0.0;
    pp.neighbours = NeighbourMode::RecomputeGrid;
    pp.split_below = 3;
    pp.kill_above = 18;
    pp.dt = 0.1;
    pp.max_substeps = 1024;
    pp.threads = 1;  // a hole's particles are few: one thread (the result does not depend on it)
    Points rigid(static_cast<Eigen::Index>(ring.size()), 3);
    for (std::size_t k = 0; k < ring.size(); ++k)
      rigid.row(static_cast<Eigen::Index>(k)) = (model.positions().row(ring[k]) - centre.transpose()) / h;
    ParticleEngine engine(ParticleState::from_surfels((sx.rowwise() - centre.transpose()) / h, sn), rigid, pp);
    HeightField unit = field;
    unit.centre = Vec3::Zero();
    unit.c[0] *= h, unit.c[1] *= h, unit.c[2] *= h, unit.c[5] /= h;
    engine.set_constraint([&unit](const Vec3& x, Vec3* n) { return unit.project(x, n); });
    for (int it = 0; it < params.iterations; ++it) engine.step();
    sx = (engine.state().x * h).rowwise() + centre.transpose();
    sn = engine.state().normals();
  }
  if (params.projection == ProjectionKind::Mls) {
    // The surface around and across the hole: the ring surfels and the particles.
    const Eigen::Index nr = static_cast<Eigen::Index>(ring.size());
    Points px(nr + sx.rows(), 3), pn(px.rows(), 3);
    for (Eigen::Index k = 0; k < nr; ++k) {
      px.row(k) = model.positions().row(ring[k]);
      pn.row(k) = model.normals().row(ring[k]);
    }
    px.bottomRows(sx.rows()) = sx;
    pn.bottomRows(sx.rows()) = sn;
    const SurfaceProjector surface(px, pn);
    project_rows_mls(surface, params.mls_width * h, sx, sn, 1);
  }
  // Keep the particles that cover something new, at least 0.5 h from a surfel and from each other.
  std::vector<Vec3> kept;
  for (Eigen::Index k = 0; k < sx.rows(); ++k) {
    const Vec3 x = sx.row(k).transpose();
    double d2 = 0.0;
    tree.nearest(x, &d2);
    if (d2 < 0.25 * h * h || !x.allFinite()) continue;
    bool close = false;
    for (const Vec3& y : kept) close = close || (x - y).squaredNorm() < 0.25 * h * h;
    if (close) continue;
    kept.push_back(x);
    const Eigen::Index q = out.positions.rows();
    out.positions.conservativeResize(q + 1, 3);
    out.normals.conservativeResize(q + 1, 3);
    out.positions.row(q) = x.transpose();
    out.normals.row(q) = sn.row(k).normalized();
    Index best = loop[0];
    double best_d2 = INFINITY;
    for (Index r : loop) {
      const double d = (model.positions().row(r).transpose() - x).squaredNorm();
      if (d < best_d2) best_d2 = d, best = r;
    }
    out.parent.push_back(best);
  }
  out.radii = Values::Constant(out.positions.rows(), h);
  return out;
}

}  // namespace surfeledit
