#include "surfeledit/core/tool.hpp"

#include <algorithm>
#include <iterator>

namespace surfeledit {

std::size_t ToolImage::bytes() const {
  const auto points = [](const Points& p) { return static_cast<std::size_t>(p.size()) * sizeof(double); };
  return sizeof(*this) + colliding.capacity() * sizeof(SurfelId) + (fields ? fields->memory_bytes() : 0) +
         (detector ? detector->memory_bytes() : 0) + points(merge.origin_positions) + points(merge.origin_normals) +
         points(merge.crease_positions) + points(merge.crease_from) +
         static_cast<std::size_t>(merge.crease_radii.size()) * sizeof(double) +
         (merge.features.capacity() + merge.crease_moved.capacity() + merge.crease_copies.capacity()) * sizeof(SurfelId);
}

ToolImage Tool::image(bool clone) const {
  ToolImage t;
  if (fields) t.fields = *fields;
  t.settings = settings;
  if (detector) t.detector = clone ? std::shared_ptr<CollisionDetector>(detector->clone()) : detector;
  t.merge = merge;
  t.colliding = colliding;
  t.steps = steps;
  t.stale = stale;
  return t;
}

void Tool::restore(const ToolImage& t, bool clone) {
  if (!t.fields_kept) {
    if (t.fields) fields = std::make_unique<DeformationFields>(*t.fields);
    else fields.reset();
  }
  settings = t.settings;
  detector = clone && t.detector ? std::shared_ptr<CollisionDetector>(t.detector->clone()) : t.detector;
  merge = t.merge;
  colliding = t.colliding;
  steps = t.steps;
  fresh_at = 0;
  fresh_object = nullptr;
  // The rows moved since are not in the image: a stale tool that comes back is re-initialised.
  clear_stale();
  if (t.stale) mark_stale(nullptr);
}

void Tool::mark_stale(const IndexList* moved) {
  if (!stale) {
    stale = true;
    stale_rows_known = moved != nullptr;
    stale_rows.clear();
    if (moved) stale_rows = *moved;
  } else if (stale_rows_known && moved) {
    IndexList both;
    both.reserve(stale_rows.size() + moved->size());
    std::set_union(stale_rows.begin(), stale_rows.end(), moved->begin(), moved->end(), std::back_inserter(both));
    stale_rows = std::move(both);
  } else {
    stale_rows_known = false;
    stale_rows.clear();
  }
  if (!stale_rows_known) {
    held_rows = IndexList();
    held = RigidRows();
  }
  if (stale_rows_known && !std::is_sorted(stale_rows.begin(), stale_rows.end())) std::sort(stale_rows.begin(), stale_rows.end());
}

void Tool::clear_stale() {
  stale = false;
  stale_rows_known = false;
  stale_rows.clear();
  held_rows = IndexList();
  held = RigidRows();
}

void Tool::hold_rigid(const SurfelModel& model, const IndexList& rows) {
  if (!detector || !fields || (stale && !stale_rows_known)) return;
  if (!stale) {  // what an op that did not move them kept is stale itself
    held_rows.clear();
    held = RigidRows();
  }
  if (std::includes(held_rows.begin(), held_rows.end(), rows.begin(), rows.end())) return;
  // Merge: the rows held keep their values (first move wins), the others take the model's now.
  IndexList both;
  both.reserve(held_rows.size() + rows.size());
  std::set_union(held_rows.begin(), held_rows.end(), rows.begin(), rows.end(), std::back_inserter(both));
  const Eigen::Index n = static_cast<Eigen::Index>(both.size());
  RigidRows out;
  out.resize(n);
  std::size_t h = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Index r = both[static_cast<std::size_t>(k)];
    if (h < held_rows.size() && held_rows[h] == r) {
      const Eigen::Index j = static_cast<Eigen::Index>(h++);
      out.positions.row(k) = held.positions.row(j);
      out.normals.row(k) = held.normals.row(j);
      out.radii[k] = held.radii[j];
    } else {
      out.positions.row(k) = model.positions().row(r);
      out.normals.row(k) = model.normals().row(r);
      out.radii[k] = model.radii()[r];
    }
  }
  held_rows = std::move(both);
  held = std::move(out);
}

bool Tool::held_before(RigidRows& out) const {
  const Eigen::Index n = static_cast<Eigen::Index>(stale_rows.size());
  out.resize(n);
  std::size_t h = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Index r = stale_rows[static_cast<std::size_t>(k)];
    while (h < held_rows.size() && held_rows[h] < r) ++h;
    if (h == held_rows.size() || held_rows[h] != r) return false;
    const Eigen::Index j = static_cast<Eigen::Index>(h);
    out.positions.row(k) = held.positions.row(j);
    out.normals.row(k) = held.normals.row(j);
    out.radii[k] = held.radii[j];
  }
  return true;
}

CollisionDetector::ResetRows Tool::merge_origins() const {
  if (!merge.origins_in_detector) return {&merge.origin_positions, &merge.origin_normals};
  const CollisionDetector::ResetRows rows = detector ? detector->reset_rows() : CollisionDetector::ResetRows{};
  if (!rows.positions || !rows.normals) throw Error(ErrorCode::Internal, "merge", "the detector lost the merge origins");
  return rows;
}

void Tool::own_origins() {
  if (!merge.origins_in_detector) return;
  const CollisionDetector::ResetRows rows = merge_origins();
  merge.origin_positions = *rows.positions;
  merge.origin_normals = *rows.normals;
  merge.origins_in_detector = false;
}

void Tool::clear_regions() {
  fields.reset();
  detector.reset();
  fresh_at = 0;
  fresh_object = nullptr;
  colliding.clear();
  merge = MergeMemo();
  clear_stale();
}

void extend_fields(DeformationFields& f, const IndexList& parents) {
  const Index first = static_cast<Index>(f.regions.size());
  // The parents' positions in f.deformable (-1: F0), found before anything grows.
  IndexList at(parents.size(), -1);
  std::size_t added = 0;
  for (std::size_t k = 0; k < parents.size(); ++k) {
    if (f.regions[static_cast<std::size_t>(parents[k])] == Region::Zero) continue;
    const auto it = std::lower_bound(f.deformable.begin(), f.deformable.end(), parents[k]);
    at[k] = static_cast<Index>(it - f.deformable.begin());
    ++added;
  }
  Eigen::Index d = static_cast<Eigen::Index>(f.deformable.size());
  const bool stored = f.blend.rows() != 0;  // none stored: every deformable row, and so every child, is F1
  if (stored) f.blend.conservativeResize(d + static_cast<Eigen::Index>(added), 4);
  for (std::size_t k = 0; k < parents.size(); ++k) {
    const Index child = first + static_cast<Index>(k);
    f.regions.push_back(f.regions[static_cast<std::size_t>(parents[k])]);
    if (at[k] < 0) continue;
    if (stored) f.blend.row(d++) = f.blend.row(at[k]);  // children come after every row: `deformable` stays ascending
    f.deformable.push_back(child);
  }
}

void compact_fields(DeformationFields& f, const std::vector<bool>& keep) {
  // New row of each kept row: its rank among the kept rows.
  std::vector<Index> new_row(f.regions.size(), -1);
  Index next = 0;
  for (std::size_t r = 0; r < f.regions.size(); ++r)
    if (keep[r]) new_row[r] = next++;
  std::size_t w = 0;
  for (std::size_t k = 0; k < f.deformable.size(); ++k) {
    const Index r = f.deformable[k];
    if (!keep[static_cast<std::size_t>(r)]) continue;
    if (f.blend.rows() != 0) f.blend.row(static_cast<Eigen::Index>(w)) = f.blend.row(static_cast<Eigen::Index>(k));
    f.deformable[w++] = new_row[static_cast<std::size_t>(r)];
  }
  f.deformable.resize(w);
  if (f.blend.rows() != 0) f.blend.conservativeResize(static_cast<Eigen::Index>(w), 4);
  w = 0;
  for (std::size_t r = 0; r < f.regions.size(); ++r)
    if (keep[r]) f.regions[w++] = f.regions[r];
  f.regions.resize(w);
}

std::size_t lock_overlap(const std::vector<Region>& a, const std::vector<Region>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  std::size_t both = 0;
  for (std::size_t r = 0; r < n; ++r) both += a[r] != Region::Zero && b[r] != Region::Zero;
  return both;
}

}  // namespace surfeledit
