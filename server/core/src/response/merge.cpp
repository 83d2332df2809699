// Merge (union) of the deformed and the zero region; see merge.hpp (thesis §11.3).
#include "surfeledit/core/response/merge.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>

#include "detail.hpp"
#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

using response_detail::Box;
using response_detail::require_at_least;

void validate(const MergeParams& params) {
  require_at_least(params.inside_margin, 0.0, "inside_margin");
  require_at_least(params.feature_radius_factor, 0.0, "feature_radius_factor");
  require_at_least(params.knn_eps, 0.0, "knn_eps");
}

namespace {

void check_inputs(const SurfelModel& model, const std::vector<Region>& regions,
                  const Points& original_positions, const Points& original_normals) {
  if (static_cast<Index>(regions.size()) != model.size()) {
    throw Error(ErrorCode::InvalidArgument, "regions",
                "has " + std::to_string(regions.size()) + " labels, expected " +
                    std::to_string(model.size()) + " (one per surfel)");
  }
  if (original_normals.rows() != original_positions.rows()) {
    throw Error(ErrorCode::InvalidArgument, "original_normals",
                "has " + std::to_string(original_normals.rows()) + " rows, expected " +
                    std::to_string(original_positions.rows()) + " (one per original position)");
  }
  require_finite(original_positions, "original_positions");
  require_finite(original_normals, "original_normals");
}

// Ids of the flagged rows, ascending (rows are in ascending id order).
IdList ids_of(const SurfelModel& model, const std::vector<bool>& flag) {
  IdList out;
  for (std::size_t r = 0; r < flag.size(); ++r)
    if (flag[r]) out.push_back(model.id_of(r));
  return out;
}

// The two sides near the deformed region, each with a k-d tree: [0] the zero surfels in the deformed
// region's bounding box (exact queries), [1] the deformable surfels (approximate, MergeParams::knn_eps).
struct Sides {
  IndexList rows[2];
  std::unique_ptr<KdTree> tree[2];
};

// The zero surfels inside the deformed region: flags #P (true = inside) over the zero candidates.
std::vector<bool> zero_inside(const SurfelModel& model, const Sides& sides, const Points& original_positions,
                              const Points& original_normals, const Box& box, const MergeParams& params,
                              MergeStats& stats) {
  const Points& pos = model.positions();
  const Points& nrm = model.normals();
  const Values& rad = model.radii();
  const IndexList& candidates = sides.rows[0];
  const KdTree& candidate_tree = *sides.tree[0];
  const KdTree& deformed = *sides.tree[1];
  stats.candidates = static_cast<Index>(candidates.size());
  KdTreeParams approximate;
  approximate.threads = 1;
  approximate.eps = params.knn_eps;
  // The closing surfels: the original deformable surfels near the deformed region.
  IndexList closing;
  if (params.close_with_originals) {
    for (Index k = 0; k < original_positions.rows(); ++k)
      if (box.contains(original_positions.row(k).transpose())) closing.push_back(k);
  }
  const KdTree originals(original_positions, closing, approximate);

  // Spatial coherence (as the Improved Simple Algo, §4.2): a candidate whose nearest surfel is at
  // distance d settles every candidate within d - max_radius (no surface passes in between), so deep
  // candidates, whose nearest-surfel queries are the slowest, are mostly never queried.
  const double max_radius = rad.maxCoeff();
  std::vector<std::int32_t> candidate_of(static_cast<std::size_t>(model.size()), -1);
  for (std::size_t c = 0; c < candidates.size(); ++c)
    candidate_of[static_cast<std::size_t>(candidates[c])] = static_cast<std::int32_t>(c);
  std::vector<std::int8_t> inside(candidates.size(), -1);
  IndexList hits;
  std::vector<double> hit_dist2;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    if (inside[c] >= 0) continue;
    ++stats.queried;
    const Index r = candidates[c];
    const Vec3 q = pos.row(r).transpose();
    const double w = -params.inside_margin * rad[r];
    double dist2_d = 0.0;
    const Index d = deformed.nearest(q, &dist2_d);
    // Distance to the nearest surfel that decides (a lower bound with approximate queries).
    double clear = std::sqrt(dist2_d / (1.0 + params.knn_eps));
    bool in = (q - pos.row(d).transpose()).dot(nrm.row(d).transpose()) <= w;
    if (in && originals.size()) {
      // The deformed region alone says inside; where an original surfel is nearer, the closed-up
      // surface decides (its normal flipped): this keeps the zero surfels beyond an open region's rim.
      double dist2_o = 0.0;
      const Index o = originals.nearest(q, &dist2_o);
      clear = std::min(clear, std::sqrt(dist2_o / (1.0 + params.knn_eps)));
      if (dist2_o < dist2_d &&
          -(q - original_positions.row(o).transpose()).dot(original_normals.row(o).transpose()) > w)
        in = false;
    }
    inside[c] = in;
    const double settle = clear - max_radius;
    if (settle <= max_radius) continue;  // too small to pay for the radius query
    candidate_tree.radius(q, settle, hits, hit_dist2);
    for (Index h : hits) {
      std::int8_t& state = inside[static_cast<std::size_t>(candidate_of[static_cast<std::size_t>(h)])];
      if (state < 0) state = in;
    }
  }
  std::vector<bool> flag(static_cast<std::size_t>(model.size()), false);
  for (std::size_t c = 0; c < candidates.size(); ++c)
    if (inside[c] == 1) {
      flag[static_cast<std::size_t>(candidates[c])] = true;
      ++stats.removed_zero;
    }
  return flag;
}

// Feature surfels (see MergeParams::feature_radius_factor): kept surfels near the rim of the removed part
// of their own surface whose estimated distance to the intersection, the offset o to the other surface
// (nearest surfel of the other side) over the sine of the angle between the two normals, is within
// reach. Only surfels near the removed set are looked at.
void mark_features(const SurfelModel& model, const Sides& sides,
                   const std::vector<bool>& removed, const MergeParams& params, MergeResult& out) {
  const Points& pos = model.positions();
  const Points& nrm = model.normals();
  const Values& rad = model.radii();
  const double gate_factor = 2.0 * params.feature_radius_factor;  // own-side removed surfel within this x r
  Box near_removed;
  for (Index r = 0; r < model.size(); ++r)
    if (removed[static_cast<std::size_t>(r)]) near_removed.add(pos.row(r).transpose());
  near_removed.grow(gate_factor * rad.maxCoeff());
  std::vector<bool> feature[2] = {std::vector<bool>(removed.size(), false),
                                  std::vector<bool>(removed.size(), false)};
  IndexList near;
  std::vector<double> near_dist2;
  for (int side = 0; side < 2; ++side) {
    for (Index r : sides.rows[side]) {
      const Vec3 p = pos.row(r).transpose();
      if (removed[static_cast<std::size_t>(r)] || !near_removed.contains(p)) continue;
      sides.tree[side]->radius(p, gate_factor * rad[r], near, near_dist2);
      if (std::none_of(near.begin(), near.end(), [&](Index h) { return removed[static_cast<std::size_t>(h)]; }))
        continue;
      const Index q = sides.tree[1 - side]->nearest(p);
      if (q < 0) continue;
      const Vec3 n_q = nrm.row(q).transpose();
      const double offset = std::max(0.0, (p - pos.row(q).transpose()).dot(n_q));
      const double sine = std::max(0.2, nrm.row(r).transpose().cross(n_q).norm());
      if (offset <= params.feature_radius_factor * rad[r] * sine) feature[side][static_cast<std::size_t>(r)] = true;
    }
  }
  out.features_deformable = ids_of(model, feature[1]);
  out.features_zero = ids_of(model, feature[0]);
}

}  // namespace

MergeResult merge_regions(const SurfelModel& model, const std::vector<Region>& regions,
                          const Points& original_positions, const Points& original_normals,
                          const IdList& colliding, const MergeParams& params) {
  const auto start = std::chrono::steady_clock::now();
  validate(params);
  check_inputs(model, regions, original_positions, original_normals);
  const IndexList colliding_rows = model.rows_of(colliding, "colliding");
  for (std::size_t k = 0; k < colliding_rows.size(); ++k) {
    if (regions[colliding_rows[k]] == Region::Zero) {
      throw Error(ErrorCode::InvalidArgument, "colliding",
                  "surfel id " + std::to_string(colliding[k]) + " is in the zero region, not deformable");
    }
  }
  MergeResult out;
  if (colliding_rows.empty()) return out;

  const Points& pos = model.positions();
  const Values& rad = model.radii();
  Sides sides;
  Box box;
  for (Index r = 0; r < model.size(); ++r) {
    if (regions[r] == Region::Zero) continue;
    sides.rows[1].push_back(r);
    box.add(pos.row(r).transpose());
  }
  box.grow(rad.maxCoeff());
  for (Index r = 0; r < model.size(); ++r)
    if (regions[r] == Region::Zero && box.contains(pos.row(r).transpose())) sides.rows[0].push_back(r);
  KdTreeParams exact;
  exact.threads = 1;
  KdTreeParams approximate = exact;
  approximate.eps = params.knn_eps;
  sides.tree[0] = std::make_unique<KdTree>(pos, sides.rows[0], exact);
  sides.tree[1] = std::make_unique<KdTree>(pos, sides.rows[1], approximate);

  std::vector<bool> removed = zero_inside(model, sides, original_positions, original_normals, box, params,
                                          out.stats);
  for (Index r : colliding_rows) removed[static_cast<std::size_t>(r)] = true;

  mark_features(model, sides, removed, params, out);
  out.removed = ids_of(model, removed);
  out.stats.merge_ms = ms_since(start);
  return out;
}

}  // namespace surfeledit
