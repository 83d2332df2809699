// Merge (union) of the deformed and the zero region; see merge.hpp (thesis §11.3).
#include "surfeledit/core/response/merge.hpp"

#include <omp.h>

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
  if (params.threads < 0) {
    throw Error(ErrorCode::InvalidArgument, "threads",
                "thread count must be >= 0, got " + std::to_string(params.threads));
  }
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
    if (flag[r]) out.push_back(model.ids()[r]);
  return out;
}

// The zero surfels inside the deformed region: flags #P (true = inside) over the zero rows in `box`.
std::vector<bool> zero_inside(const SurfelModel& model, const std::vector<Region>& regions,
                              const IndexList& deformable, const Points& original_positions,
                              const Points& original_normals, const Box& box, const MergeParams& params,
                              MergeStats& stats) {
  const Points& pos = model.positions();
  const Points& nrm = model.normals();
  const Values& rad = model.radii();
  IndexList candidates;
  for (Index r = 0; r < model.size(); ++r)
    if (regions[r] == Region::Zero && box.contains(pos.row(r).transpose())) candidates.push_back(r);
  stats.candidates = static_cast<Index>(candidates.size());

  KdTreeParams tp;
  tp.threads = 1;
  const KdTree deformed(pos, deformable, tp);
  // The closing surfels: the original deformable surfels near the deformed region.
  IndexList closing;
  if (params.close_with_originals) {
    for (Index k = 0; k < original_positions.rows(); ++k)
      if (box.contains(original_positions.row(k).transpose())) closing.push_back(k);
  }
  const KdTree originals(original_positions, closing, tp);

  std::vector<std::uint8_t> inside(candidates.size(), 0);
  const int threads = resolve_threads(params.threads);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const Index r = candidates[c];
    const Vec3 q = pos.row(r).transpose();
    const double w = -params.inside_margin * rad[r];
    double dist2_d = 0.0;
    const Index d = deformed.nearest(q, &dist2_d);
    if ((q - pos.row(d).transpose()).dot(nrm.row(d).transpose()) > w) continue;  // outside
    // The deformed region alone says inside; where an original surfel is nearer, the closed-up
    // surface decides (its normal flipped): this keeps the zero surfels beyond an open region's rim.
    double dist2_o = 0.0;
    const Index o = originals.size() ? originals.nearest(q, &dist2_o) : -1;
    if (o >= 0 && dist2_o < dist2_d &&
        -(q - original_positions.row(o).transpose()).dot(original_normals.row(o).transpose()) > w)
      continue;
    inside[c] = 1;
  }
  std::vector<bool> flag(static_cast<std::size_t>(model.size()), false);
  for (std::size_t c = 0; c < candidates.size(); ++c)
    if (inside[c]) {
      flag[static_cast<std::size_t>(candidates[c])] = true;
      ++stats.removed_zero;
    }
  return flag;
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
  IndexList deformable;
  Box box;
  double max_radius = 0.0;
  for (Index r = 0; r < model.size(); ++r) {
    if (regions[r] == Region::Zero) continue;
    deformable.push_back(r);
    box.add(pos.row(r).transpose());
    max_radius = std::max(max_radius, rad[r]);
  }
  box.grow(max_radius);

  std::vector<bool> removed = zero_inside(model, regions, deformable, original_positions,
                                          original_normals, box, params, out.stats);
  for (Index r : colliding_rows) removed[static_cast<std::size_t>(r)] = true;

  // Feature surfels: kept surfels near a removed one (either side), looked for near the removed set.
  IndexList removed_rows;
  Box near_removed;
  double max_all = 0.0;
  for (Index r = 0; r < model.size(); ++r) {
    max_all = std::max(max_all, rad[r]);
    if (!removed[static_cast<std::size_t>(r)]) continue;
    removed_rows.push_back(r);
    near_removed.add(pos.row(r).transpose());
  }
  near_removed.grow(params.feature_radius_factor * max_all);
  KdTreeParams tp;
  tp.threads = 1;
  const KdTree removed_tree(pos, removed_rows, tp);
  std::vector<bool> feat_d(removed.size(), false), feat_z(removed.size(), false);
  for (Index r = 0; r < model.size(); ++r) {
    if (removed[static_cast<std::size_t>(r)] || !near_removed.contains(pos.row(r).transpose())) continue;
    double dist2 = 0.0;
    removed_tree.nearest(pos.row(r).transpose(), &dist2);
    const double reach = params.feature_radius_factor * rad[r];
    if (dist2 > reach * reach) continue;
    (regions[r] == Region::Zero ? feat_z : feat_d)[static_cast<std::size_t>(r)] = true;
  }
  out.removed = ids_of(model, removed);
  out.features_deformable = ids_of(model, feat_d);
  out.features_zero = ids_of(model, feat_z);
  out.stats.merge_ms = ms_since(start);
  return out;
}

}  // namespace surfeledit
