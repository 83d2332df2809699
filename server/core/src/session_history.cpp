// EditSession's history: capturing and restoring images of the session, recording entries, undo and
// redo (history.hpp).
#include <algorithm>
#include <cstring>
#include <unordered_set>

#include "surfeledit/core/edit_session.hpp"

namespace surfeledit {

namespace {

// Rows `rows` of `a` (#rows by 3); empty when `a` is empty.
// (Points are row-major: row r is the 3 doubles at data() + 3 r.)
Points take_rows(const Points& a, const IndexList& rows) {
  if (a.rows() == 0) return Points();
  Points out(static_cast<Eigen::Index>(rows.size()), 3);
  const double* from = a.data();
  double* to = out.data();
  for (std::size_t k = 0; k < rows.size(); ++k) std::memcpy(to + 3 * k, from + 3 * rows[k], 3 * sizeof(double));
  return out;
}

void put_rows(Points& a, const IndexList& rows, const Points& values) {
  if (values.rows() == 0) return;
  const double* from = values.data();
  double* to = a.data();
  for (std::size_t k = 0; k < rows.size(); ++k) std::memcpy(to + 3 * rows[k], from + 3 * k, 3 * sizeof(double));
}

}  // namespace

SessionImage EditSession::capture_rows(const IndexList& rows, bool subset) const {
  SessionImage image;
  RowsImage r;
  r.rows = rows;
  const SurfelArrays& a = model_.arrays();
  r.positions = take_rows(a.positions, rows);
  r.normals = take_rows(a.normals, rows);
  if (model_.has_tangents()) {
    r.tangent_u = take_rows(a.tangent_u, rows);
    r.tangent_v = take_rows(a.tangent_v, rows);
  }
  r.row_version.reserve(rows.size());
  for (Index row : rows) r.row_version.push_back(row_version_[row]);
  image.rows = std::move(r);
  if (detector_) {
    image.detector = detector_->save_image(subset ? &rows : nullptr);
    image.complete = image.detector != nullptr;
  }
  image.colliding = colliding_;
  image.steps = steps_;
  return image;
}

SessionImage EditSession::capture_whole(bool clone) const {
  SessionImage image;
  WholeImage w;
  w.model = model_;
  w.model_version = model_version_;
  w.row_version = row_version_;
  if (fields_) w.fields = *fields_;
  w.settings = settings_;
  w.rest_radius = rest_radius_;
  w.merge = merge_;
  if (detector_) {
    w.detector = clone ? std::shared_ptr<CollisionDetector>(detector_->clone()) : detector_;
    image.complete = w.detector != nullptr;
  }
  image.whole = std::move(w);
  image.colliding = colliding_;
  image.steps = steps_;
  return image;
}

void EditSession::restore(const SessionImage& image, bool clone) {
  if (!image.complete) throw Error(ErrorCode::Internal, "history", "the image holds no detector state");
  if (image.rows) {
    const RowsImage& r = *image.rows;
    SurfelArrays& a = model_.arrays();
    put_rows(a.positions, r.rows, r.positions);
    put_rows(a.normals, r.rows, r.normals);
    put_rows(a.tangent_u, r.rows, r.tangent_u);
    put_rows(a.tangent_v, r.rows, r.tangent_v);
    for (std::size_t k = 0; k < r.rows.size(); ++k) row_version_[r.rows[k]] = r.row_version[k];
    if (image.detector) detector_->restore_image(*image.detector);
  } else {
    const WholeImage& w = *image.whole;
    model_ = w.model;
    model_version_ = w.model_version;
    row_version_ = w.row_version;
    if (w.fields) fields_ = std::make_unique<DeformationFields>(*w.fields);
    else fields_.reset();
    settings_ = w.settings;
    rest_radius_ = w.rest_radius;
    merge_ = w.merge;
    detector_ = clone && w.detector ? std::shared_ptr<CollisionDetector>(w.detector->clone()) : w.detector;
  }
  colliding_ = image.colliding;
  steps_ = image.steps;
}

std::size_t EditSession::history_limit() const {
  return static_cast<std::size_t>(settings_.history.history_mb * 1024.0 * 1024.0);
}

void EditSession::record(const char* op, const std::string& author, IdList touched, SessionImage before) {
  if (!std::is_sorted(touched.begin(), touched.end())) std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  HistoryEntry e;
  e.item = {version_, op, author, std::move(touched), false};
  e.image = std::move(before);
  history_.push(std::move(e), history_limit());
}

std::uint64_t EditSession::swap_entry(HistoryEntry& entry, const char* what) {
  if (!entry.image.complete) {
    throw Error(ErrorCode::Conflict, "history",
                std::string("cannot ") + what + " '" + entry.item.op +
                    "': its detector state was not saved (hierarchies and approximate detection keep no history)");
  }
  SessionImage now = entry.image.rows ? capture_rows(entry.image.rows->rows) : capture_whole(false);
  const IdList ids_before = model_.ids();
  restore(entry.image, false);
  history_.replace_image(entry, std::move(now));
  // The restored rows count as changed now; ids that went away are logged as removed.
  ++version_;
  if (entry.item.op == "load") model_version_ = version_;
  std::unordered_set<SurfelId> touched(entry.item.touched.begin(), entry.item.touched.end());
  const IdList& ids = model_.ids();
  for (std::size_t r = 0; r < ids.size(); ++r)
    if (touched.count(ids[r])) row_version_[r] = version_;
  for (SurfelId id : ids_before)
    if (model_.row_of(id) < 0) removed_log_.emplace_back(version_, id);
  return version_;
}

std::uint64_t EditSession::undo() {
  HistoryEntry* e = history_.undo_target();
  if (!e) throw Error(ErrorCode::Conflict, "history", "nothing to undo in session '" + name_ + "'");
  const std::uint64_t v = swap_entry(*e, "undo");
  history_.undone();
  return v;
}

std::uint64_t EditSession::redo() {
  HistoryEntry* e = history_.redo_target();
  if (!e) throw Error(ErrorCode::Conflict, "history", "nothing to redo in session '" + name_ + "'");
  const std::uint64_t v = swap_entry(*e, "redo");
  history_.redone();
  return v;
}

}  // namespace surfeledit
