// EditSession's blend tool, boolean operations and hole filling (thesis §12.3-12.4, docs/particles.md).
// Each computes everything on the model as it is, then changes the session in one go and records one
// history entry with the whole image before it (undo restores model, clips, fields, detector, memo).
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// Tangent axes of a surfel turned to the new unit normal `n`: u projected into the new tangent plane, v =
// n x u, both keeping their lengths (a degenerate projection takes any axis normal to n).
void turn_tangents(const Vec3& n, Vec3& u, Vec3& v) {
  const double lu = u.norm(), lv = v.norm();
  Vec3 t = u - u.dot(n) * n;
  if (t.norm() < 1e-12 * std::max(lu, 1e-300)) t = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n);
  t.normalize();
  u = lu * t;
  v = lv * n.cross(t);
}

// Surfels to insert at `positions` / `normals` with `radii`, colours and tangents from the `parents` rows
// of `model` (when it has them), unclipped.
SurfelArrays new_surfels(const SurfelModel& model, const Points& positions, const Points& normals,
                         const Values& radii, const IndexList& parents) {
  SurfelArrays a;
  a.positions = positions;
  a.normals = normals;
  a.radii = radii;
  const Eigen::Index n = positions.rows();
  if (model.has_tangents()) {
    a.tangent_u.resize(n, 3);
    a.tangent_v.resize(n, 3);
    for (Eigen::Index k = 0; k < n; ++k) {
      const double scale = radii[k] / model.radii()[parents[k]];
      Vec3 u = scale * model.tangent_u().row(parents[k]).transpose();
      Vec3 v = scale * model.tangent_v().row(parents[k]).transpose();
      turn_tangents(normals.row(k).transpose().normalized(), u, v);
      a.tangent_u.row(k) = u.transpose();
      a.tangent_v.row(k) = v.transpose();
    }
  }
  if (model.has_colors()) {
    a.colors.resize(n, 3);
    for (Eigen::Index k = 0; k < n; ++k) a.colors.row(k) = model.colors().row(parents[k]);
  }
  return a;
}

// Ids of `ids` that are still in `model`, in order.
IdList still_there(const SurfelModel& model, const IdList& ids) {
  IdList out;
  for (SurfelId id : ids)
    if (model.row_of(id) >= 0) out.push_back(id);
  return out;
}

}  // namespace

void EditSession::extend_any(const IndexList& parents) { extend_rows(parents); }

BlendOutcome EditSession::blend(const BlendParams& requested, const std::optional<IdList>& features,
                                const std::string& author) {
  const auto start = std::chrono::steady_clock::now();
  const SurfelModel& m = model();
  use(author);
  BlendParams params = requested;
  params.neighbour_factor = tool_->settings.blend.neighbour_factor;
  params.gamma = tool_->settings.blend.gamma;
  params.threads = params_.threads;
  if (tool_->merge.open_region && !features) {
    params.spring_r0 = tool_->settings.blend.spring_r0;
    if (tool_->settings.blend.open_region == OpenRegionForce::Spring) params.repulsion = RepulsionKind::Spring;
    if (tool_->settings.blend.open_region == OpenRegionForce::None) params.repulsion = RepulsionKind::None;
  }
  validate(params);
  if (features && features->empty()) throw Error(ErrorCode::InvalidArgument, "features", "features is empty");
  if (!features && tool_->merge.features.empty())
    throw Error(ErrorCode::Conflict, "features",
                "no merge or boolean with feature surfels in session '" + name_ + "' yet: pass features=ids");
  const IdList& seed_ids = features ? *features : tool_->merge.features;
  const IndexList seed_rows = m.rows_of(seed_ids, "features");
  const BlendRegion region = blend_region(m, seed_rows, params.range_factor);

  // Undo the crease in the region (§12.3.1): moved surfels back, copies out (not particles).
  std::vector<Index> crease_from_row(static_cast<std::size_t>(m.size()), -1);
  for (std::size_t k = 0; k < tool_->merge.crease_moved.size(); ++k) {
    const Index r = m.row_of(tool_->merge.crease_moved[k]);
    if (r >= 0) crease_from_row[r] = static_cast<Index>(k);
  }
  std::vector<bool> is_copy(static_cast<std::size_t>(m.size()), false);
  for (SurfelId id : tool_->merge.crease_copies)
    if (m.row_of(id) >= 0) is_copy[m.row_of(id)] = true;
  IndexList rows;  // the particles' rows
  IdList removed;
  for (Index r : region.rows) {
    if (is_copy[r]) removed.push_back(m.id_of(r));
    else rows.push_back(r);
  }
  Points x(static_cast<Eigen::Index>(rows.size()), 3), n(x.rows(), 3);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Index r = rows[k], c = crease_from_row[r];
    if (c >= 0) x.row(static_cast<Eigen::Index>(k)) = tool_->merge.crease_from.row(c);
    else x.row(static_cast<Eigen::Index>(k)) = m.positions().row(r);
    n.row(static_cast<Eigen::Index>(k)) = m.normals().row(r);
  }
  Points rigid(static_cast<Eigen::Index>(region.rigid.size()), 3), rigid_n(rigid.rows(), 3);
  for (std::size_t k = 0; k < region.rigid.size(); ++k) {
    rigid.row(static_cast<Eigen::Index>(k)) = m.positions().row(region.rigid[k]);
    rigid_n.row(static_cast<Eigen::Index>(k)) = m.normals().row(region.rigid[k]);
  }
  const BlendRun run = run_blend(x, n, rigid, m.radii().mean(), params, rigid_n);

  // Particles back to surfels: the first particle of each region surfel keeps its id, split-off ones are new.
  BlendOutcome out;
  out.particles = static_cast<Index>(rows.size());
  out.energy.assign(run.energy.data(), run.energy.data() + run.energy.size());
  out.substeps = run.substeps;
  std::vector<Eigen::Index> particle_of(rows.size(), -1);
  IndexList parents;
  std::vector<Eigen::Index> split_particles;
  // Pass 1: the particles that are the surfels themselves; pass 2: a copy takes over its surfel's id when
  // the surfel's own particle was killed, else it is a new surfel.
  for (std::size_t q = 0; q < run.origin.size(); ++q)
    if (run.origin[q] >= 0) particle_of[static_cast<std::size_t>(run.origin[q])] = static_cast<Eigen::Index>(q);
  for (std::size_t q = 0; q < run.origin.size(); ++q) {
    if (run.origin[q] >= 0) continue;
    const std::size_t k = static_cast<std::size_t>(-1 - run.origin[q]);
    if (particle_of[k] < 0) {
      particle_of[k] = static_cast<Eigen::Index>(q);
      continue;
    }
    split_particles.push_back(static_cast<Eigen::Index>(q));
    parents.push_back(rows[k]);
  }
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (particle_of[k] < 0) removed.push_back(m.id_of(rows[k]));
    else out.moved.push_back(m.id_of(rows[k]));
  }
  std::sort(removed.begin(), removed.end());
  std::vector<bool> keep(static_cast<std::size_t>(m.size()), true);
  for (Index r : m.rows_of(removed, "removed")) keep[r] = false;
  check_regions_kept(keep, "blend");
  {
    IndexList changed = rows;  // the particles move; split-off ones copy their surfel
    changed.insert(changed.end(), parents.begin(), parents.end());
    check_unlocked(&keep, &changed, "blend");
  }
  Points sp(static_cast<Eigen::Index>(split_particles.size()), 3), sn(sp.rows(), 3);
  Values sr(sp.rows());
  for (std::size_t k = 0; k < split_particles.size(); ++k) {
    sp.row(static_cast<Eigen::Index>(k)) = run.positions.row(split_particles[k]);
    sn.row(static_cast<Eigen::Index>(k)) = run.normals.row(split_particles[k]);
    sr[static_cast<Eigen::Index>(k)] = m.radii()[parents[k]];
  }
  SurfelArrays added = new_surfels(m, sp, sn, sr, parents);
  validate_arrays(added, m.has_tangents(), m.has_colors());

  // Apply.
  SessionImage before = capture_whole(false);
  ++version_;
  SurfelArrays& a = model_.arrays();
  IndexList touched_rows;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (particle_of[k] < 0) continue;
    const Index r = rows[k];
    const Vec3 nr = run.normals.row(particle_of[k]).transpose().normalized();
    a.positions.row(r) = run.positions.row(particle_of[k]);
    a.normals.row(r) = nr.transpose();
    if (model_.has_tangents()) {
      Vec3 u = a.tangent_u.row(r).transpose(), v = a.tangent_v.row(r).transpose();
      turn_tangents(nr, u, v);
      a.tangent_u.row(r) = u.transpose();
      a.tangent_v.row(r) = v.transpose();
    }
    if (model_.has_clips()) {
      a.clip_points.row(r).setZero();
      a.clip_dirs.row(r).setZero();
    }
    touched_rows.push_back(r);
  }
  touch_rows(touched_rows);
  IdList blended = out.moved;
  if (!removed.empty()) remove_rows(removed, keep);
  out.inserted = model_.insert(std::move(added));
  IndexList parent_rows;
  const IndexList new_row = remap_rows(keep);
  for (Index r : parents) parent_rows.push_back(new_row[r]);
  extend_any(parent_rows);
  out.removed = removed;
  if (tool_->fields) {
    tool_->detector = fresh_detector(tool_->settings, *tool_->fields);
    take_origins();
  }
  tool_->colliding.clear();
  // The crease is undone where the blend ran; the features stay (a second call continues the blend).
  IdList moved_left, copies_left;
  Points from_left(0, 3);
  for (std::size_t k = 0; k < tool_->merge.crease_moved.size(); ++k) {
    const Index r = model_.row_of(tool_->merge.crease_moved[k]);
    if (r < 0 || std::binary_search(blended.begin(), blended.end(), tool_->merge.crease_moved[k])) continue;
    moved_left.push_back(tool_->merge.crease_moved[k]);
    from_left.conservativeResize(from_left.rows() + 1, 3);
    from_left.row(from_left.rows() - 1) = tool_->merge.crease_from.row(static_cast<Eigen::Index>(k));
  }
  tool_->merge.crease_moved = moved_left;
  tool_->merge.crease_from = from_left;
  tool_->merge.crease_copies = still_there(model_, tool_->merge.crease_copies);
  tool_->merge.features = still_there(model_, tool_->merge.features);
  IdList touched = out.moved;
  touched.insert(touched.end(), out.inserted.begin(), out.inserted.end());
  touched.insert(touched.end(), out.removed.begin(), out.removed.end());
  record("blend", author, std::move(touched), std::move(before));
  out.ms = ms_since(start);
  return out;
}

MergeOutcome EditSession::boolean(BooleanOp op, SurfelArrays b, const BooleanParams& params,
                                  const std::string& author) {
  const auto start = std::chrono::steady_clock::now();
  const SurfelModel& m = model();
  validate(params);
  if (b.clip_points.rows() > 0 || b.clip_dirs.rows() > 0)
    throw Error(ErrorCode::InvalidArgument, "clips", "model B may not carry clip lines");
  SurfelModel bm = SurfelModel::from_arrays(std::move(b));  // validates, normalises, estimates radii
  BooleanParams bp = params;
  bp.threads = params_.threads;
  const BooleanClassification c =
      classify_boolean(m.positions(), m.normals(), m.radii(), bm.positions(), bm.normals(), bm.radii(), op, bp);
  MergeOutcome out;
  out.merge_ms = ms_since(start);
  std::vector<bool> keep(static_cast<std::size_t>(m.size()), true);
  Index kept_a = 0;
  for (Index r = 0; r < m.size(); ++r) {
    keep[r] = c.keep_a[r];
    if (keep[r]) ++kept_a;
    else out.removed.push_back(m.id_of(r));
  }
  IndexList b_rows;  // kept rows of B
  for (Index r = 0; r < bm.size(); ++r)
    if (c.keep_b[r]) b_rows.push_back(r);
  if (kept_a + static_cast<Index>(b_rows.size()) == 0)
    throw Error(ErrorCode::Conflict, "op", std::string("the ") + enum_name(op) + " of the two models is empty");
  const double flip = op == BooleanOp::Difference ? -1.0 : 1.0;
  SurfelArrays added;
  const Eigen::Index nb = static_cast<Eigen::Index>(b_rows.size());
  added.positions.resize(nb, 3);
  added.normals.resize(nb, 3);
  added.radii.resize(nb);
  for (Eigen::Index k = 0; k < nb; ++k) {
    added.positions.row(k) = bm.positions().row(b_rows[k]);
    added.normals.row(k) = flip * bm.normals().row(b_rows[k]);
    added.radii[k] = bm.radii()[b_rows[k]];
  }
  if (m.has_tangents()) {
    added.tangent_u.resize(nb, 3);
    added.tangent_v.resize(nb, 3);
    for (Eigen::Index k = 0; k < nb; ++k) {
      const Vec3 nk = added.normals.row(k).transpose();
      const Vec3 u = added.radii[k] * (std::abs(nk.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(nk).normalized();
      const Vec3 v = added.radii[k] * nk.cross(u.normalized());
      added.tangent_u.row(k) = u.transpose();
      added.tangent_v.row(k) = v.transpose();
    }
  }
  if (m.has_colors()) added.colors = Colors::Constant(nb, 3, 200);

  IdList features_a;  // A's ids stay (read before the model changes: `m` is the live model)
  for (Index r : c.features_a) features_a.push_back(m.id_of(r));

  // Apply: B's surfels appended, A's dropped ones removed, regions cleared.
  use(author);
  SessionImage before = capture_whole(false);
  ++version_;
  for (auto& [id, t] : tools_) t.clear_regions();  // the model's shape changed as by a load
  rest_radius_ = Values();
  out.inserted = nb > 0 ? model_.insert(std::move(added)) : IdList{};
  row_version_.resize(static_cast<std::size_t>(model_.size()), version_);
  keep.resize(static_cast<std::size_t>(model_.size()), true);
  if (!out.removed.empty()) remove_rows(out.removed, keep);
  out.features = std::move(features_a);
  std::vector<Index> b_new(static_cast<std::size_t>(bm.size()), -1);
  for (std::size_t k = 0; k < b_rows.size(); ++k) b_new[b_rows[k]] = static_cast<Index>(k);
  for (Index r : c.features_b) out.features.push_back(out.inserted[b_new[r]]);
  std::sort(out.features.begin(), out.features.end());
  tool_->merge = MergeMemo();
  tool_->merge.features = out.features;
  tool_->merge.open_region = true;
  IdList touched = out.removed;
  touched.insert(touched.end(), out.inserted.begin(), out.inserted.end());
  record("boolean", author, std::move(touched), std::move(before));
  out.total_ms = ms_since(start);
  return out;
}

FillOutcome EditSession::fill_holes(const HoleParams& requested, const std::optional<IdList>& boundary,
                                    const std::string& author) {
  const auto start = std::chrono::steady_clock::now();
  const SurfelModel& m = model();
  HoleParams params = requested;
  params.threads = params_.threads;
  validate(params);
  if (boundary && boundary->empty()) throw Error(ErrorCode::InvalidArgument, "boundary", "boundary is empty");
  const IndexList brows = boundary ? m.rows_of(*boundary, "boundary") : boundary_rows(m, params);
  IndexList sorted = brows;
  std::sort(sorted.begin(), sorted.end());
  FillOutcome out;
  Points pos(0, 3), nrm(0, 3);
  Values rad(0);
  IndexList parents;
  std::vector<std::size_t> count;  // surfels per filled hole
  for (const Hole& h : group_loops(m, sorted, params)) {
    if (h.diameter > params.max_diameter) {
      ++out.skipped;
      continue;
    }
    const HoleFilling f = fill_hole(m, h, params);
    HoleOutcome ho;
    for (Index r : h.boundary) ho.boundary.push_back(m.id_of(r));
    ho.diameter = h.diameter;
    out.holes.push_back(std::move(ho));
    count.push_back(static_cast<std::size_t>(f.positions.rows()));
    const Eigen::Index n0 = pos.rows(), q = f.positions.rows();
    pos.conservativeResize(n0 + q, 3);
    nrm.conservativeResize(n0 + q, 3);
    rad.conservativeResize(n0 + q);
    pos.bottomRows(q) = f.positions;
    nrm.bottomRows(q) = f.normals;
    rad.tail(q) = f.radii;
    parents.insert(parents.end(), f.parent.begin(), f.parent.end());
  }
  if (pos.rows() == 0) {
    out.ms = ms_since(start);
    return out;
  }
  SurfelArrays added = new_surfels(m, pos, nrm, rad, parents);
  validate_arrays(added, m.has_tangents(), m.has_colors());
  use(author);
  check_unlocked(nullptr, &parents, "boundary");
  SessionImage before = capture_whole(false);
  ++version_;
  out.inserted = model_.insert(std::move(added));
  extend_any(parents);
  if (tool_->fields) {
    tool_->detector = fresh_detector(tool_->settings, *tool_->fields);
    take_origins();
  }
  tool_->colliding.clear();
  std::size_t at = 0;
  for (std::size_t k = 0; k < out.holes.size(); ++k) {
    out.holes[k].inserted.assign(out.inserted.begin() + at, out.inserted.begin() + at + count[k]);
    at += count[k];
  }
  record("fill_holes", author, out.inserted, std::move(before));
  out.ms = ms_since(start);
  return out;
}

}  // namespace surfeledit
