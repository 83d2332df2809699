// EditSession's merge response (docs/algorithms.md §7 d, thesis §11.3): merge_regions, then the sharp
// crease, on the session's model; the detector re-initialises from the merged model.
#include <algorithm>
#include <chrono>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/response/crease.hpp"
#include "surfeledit/core/response/merge.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// Rows `rows` of `a`, #rows by 3.
Points gather(const Points& a, const IndexList& rows) {
  Points out(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = a.row(rows[k]);
  return out;
}

}  // namespace

void EditSession::take_origins() {
  // The detector was just reset from this model with these fields: when it keeps the deformable rows it saw,
  // they are the origins (the same rows, in the same order).
  const CollisionDetector::ResetRows kept = tool_->detector ? tool_->detector->reset_rows() : CollisionDetector::ResetRows{};
  const auto d = static_cast<Eigen::Index>(tool_->fields->deformable.size());
  MergeMemo& m = tool_->merge;
  m.origins_in_detector = kept.positions && kept.normals && kept.positions->rows() == d && kept.normals->rows() == d;
  if (m.origins_in_detector) {
    m.origin_positions.resize(0, 3);
    m.origin_normals.resize(0, 3);
  } else {
    m.origin_positions = gather(model_.positions(), tool_->fields->deformable);
    m.origin_normals = gather(model_.normals(), tool_->fields->deformable);
  }
}

void EditSession::extend_rows(const IndexList& parents, bool skip_acting) {
  const Index rows = model_.size();
  const Index first = rows - static_cast<Index>(parents.size());
  for (auto& [id, t] : tools_)
    if (t.fields && !(skip_acting && &t == tool_)) extend_fields(*t.fields, parents);
  if (rest_radius_.size() > 0) {
    rest_radius_.conservativeResize(rows);
    for (std::size_t k = 0; k < parents.size(); ++k) rest_radius_[first + static_cast<Index>(k)] = rest_radius_[parents[k]];
  }
  row_version_.resize(static_cast<std::size_t>(rows), version_);
}

MergeOutcome EditSession::merge(bool crease, const std::string& author) {
  model();  // throws without a model
  const Tool* own = find_tool(author);
  if (!own || !own->fields) throw Error(ErrorCode::Conflict, "regions", "set the zero and one regions before merging");
  use(author);
  const std::uint64_t version_before = version_;
  // The detector is replaced (reset from the merged model): the live one can be the image's.
  SessionImage before = capture_whole(false);
  MergeOutcome out = merge_now(crease);
  if (version_ == version_before) return out;  // nothing collided: no change
  IdList touched = out.removed;
  touched.insert(touched.end(), out.moved.begin(), out.moved.end());
  touched.insert(touched.end(), out.inserted.begin(), out.inserted.end());
  record("merge", author, std::move(touched), std::move(before));
  return out;
}

MergeOutcome EditSession::merge_now(bool crease_on) {
  const auto start = std::chrono::steady_clock::now();
  MergeOutcome out;
  if (tool_->colliding.empty()) return out;
  // Everything is computed and validated on the model as it is; only then does the session change.
  auto t = std::chrono::steady_clock::now();
  const CollisionDetector::ResetRows origins = tool_->merge_origins();
  const MergeResult m = merge_regions(model_, tool_->fields->regions, *origins.positions, *origins.normals, tool_->colliding);
  out.merge_ms = ms_since(t);
  std::vector<bool> keep(static_cast<std::size_t>(model_.size()), true);
  for (Index r : model_.rows_of(m.removed, "removed")) keep[r] = false;
  check_regions_kept(keep, "merge");
  t = std::chrono::steady_clock::now();
  CreaseResult c;
  if (crease_on) c = crease(model_, m.features_deformable, m.features_zero);
  {
    // Nothing another tool's lock holds is removed, moved by the crease or copied.
    IndexList changed = model_.rows_of(c.moved, "moved");
    const IndexList copied = model_.rows_of(c.inserted_parents, "inserted_parents");
    changed.insert(changed.end(), copied.begin(), copied.end());
    check_unlocked(&keep, &changed, "merge");
  }
  Points crease_from(static_cast<Eigen::Index>(c.moved.size()), 3);
  for (std::size_t k = 0; k < c.moved.size(); ++k)
    crease_from.row(static_cast<Eigen::Index>(k)) = model_.positions().row(model_.row_of(c.moved[k]));
  out.removed = m.removed;
  std::set_union(m.features_deformable.begin(), m.features_deformable.end(), m.features_zero.begin(),
                 m.features_zero.end(), std::back_inserter(out.features));
  ++version_;
  remove_rows(m.removed, keep);
  out.inserted = apply_crease(model_, c);  // kept surfels only: valid after the removal
  out.moved = c.moved;
  IndexList parents = model_.rows_of(c.inserted_parents, "inserted_parents");
  extend_rows(parents);
  touch_rows(model_.rows_of(c.moved, "moved"));
  out.crease_ms = ms_since(t);
  tool_->detector = fresh_detector(tool_->settings, *tool_->fields);
  take_origins();
  tool_->colliding.clear();
  tool_->merge.crease_positions = c.positions;
  tool_->merge.features = out.features;
  tool_->merge.crease_moved = c.moved;
  tool_->merge.crease_from = std::move(crease_from);
  tool_->merge.crease_copies = out.inserted;
  tool_->merge.open_region = false;
  tool_->merge.crease_radii.resize(static_cast<Eigen::Index>(c.moved.size()));
  const IndexList moved_rows = model_.rows_of(c.moved, "moved");
  for (std::size_t k = 0; k < moved_rows.size(); ++k)
    tool_->merge.crease_radii[static_cast<Eigen::Index>(k)] = model_.radii()[moved_rows[k]];
  t = std::chrono::steady_clock::now();
  if (tool_->merge.crease_positions.rows() > 0) out.curves = intersection_curves({}, tool_id_);
  out.curves_ms = ms_since(t);
  out.total_ms = ms_since(start);
  return out;
}

std::vector<Curve> EditSession::intersection_curves(const CurveParams& params, const std::string& tool) const {
  validate(params);
  const Tool* t = find_tool(tool);
  if (!t || t->merge.crease_positions.rows() == 0)
    throw Error(ErrorCode::Conflict, "merge", "no merge with a crease in session '" + name_ + "' yet");
  return surfeledit::intersection_curves(t->merge.crease_positions, t->merge.crease_radii, params);
}

}  // namespace surfeledit
