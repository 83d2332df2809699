// EditSession's history: capturing and restoring images of the session, recording entries, undo and
// redo (history.hpp).
#include <algorithm>
#include <cstring>
#include <unordered_set>

#include "row_copy.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// `ids` made ascending and unique, and shared (an entry's touched ids).
std::shared_ptr<const IdList> shared_ascending(IdList ids) {
  if (!std::is_sorted(ids.begin(), ids.end())) std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return std::make_shared<const IdList>(std::move(ids));
}

// Sizes `out` for rows `rows` of `a` (#rows by 3, its buffer reused when the size fits; empty when `a` is
// empty) and adds the copy that fills it (and row rows[k] of `also`, #P by 3, when given).
void take_rows(const Points& a, const IndexList& rows, Points& out, std::vector<detail::RowCopy>& copies,
               double* also = nullptr) {
  if (a.rows() == 0) {
    out.resize(0, 3);
    return;
  }
  out.resize(static_cast<Eigen::Index>(rows.size()), 3);
  copies.push_back({a.data(), &rows, out.data(), false, also});
}

// Row versions of `rows` from their runs.
void put_versions(RowVersions& row_version, const IndexList& rows,
                  const std::vector<std::pair<std::uint64_t, std::uint32_t>>& runs) {
  std::size_t k = 0;
  for (const auto& [v, n] : runs)
    for (std::uint32_t j = 0; j < n; ++j) row_version.set(static_cast<std::size_t>(rows[k++]), v);
}

void put_rows(Points& a, const IndexList& rows, const Points& values) {
  if (values.rows() == 0) return;
  const double* from = values.data();
  double* to = a.data();
  for (std::size_t k = 0; k < rows.size(); ++k) std::memcpy(to + 3 * rows[k], from + 3 * k, 3 * sizeof(double));
}

// A rows image's arrays back into the model's (normals and tangents of its `bent` rows only, when it has them).
void put_image_rows(SurfelArrays& a, const RowsImage& r) {
  const IndexList& turned = r.bent ? *r.bent : *r.rows;
  put_rows(a.positions, *r.rows, r.positions);
  put_rows(a.normals, turned, r.normals);
  put_rows(a.tangent_u, turned, r.tangent_u);
  put_rows(a.tangent_v, turned, r.tangent_v);
}

}  // namespace

std::shared_ptr<const IndexList> EditSession::step_bent_rows(const DeformParams& params) {
  if (params.angle != 0.0 || !tool_->fields) return nullptr;
  // Without rotation a row whose blend gradient is 0 keeps its normal and tangents bit for bit
  // (deformation_kernel.hpp: the flat path); F1 rows have lambda 1 and gradient 0 (DeformationFields).
  const DeformationFields& f = *tool_->fields;
  // Shared while it does not change (step after step), like the row list: one pass compares it with the last list
  // and only starts a new one where they part, so a drag's steps build none (at 1M surfels ~1 MB each).
  const IndexList* last = tool_->shared_bent.get();
  std::size_t same = 0;  // leading bent rows equal to the last list's
  bool parted = last == nullptr;
  IndexList bent;
  for (const Index r : f.deformable) {
    if (f.regions[static_cast<std::size_t>(r)] == Region::One) continue;
    if (!parted) {
      if (same < last->size() && (*last)[same] == r) {
        ++same;
        continue;
      }
      parted = true;
      bent.assign(last->begin(), last->begin() + static_cast<std::ptrdiff_t>(same));
    }
    bent.push_back(r);
  }
  if (!parted) {  // the bent rows are the last list's first `same`
    if (same == last->size()) return same == f.deformable.size() ? nullptr : tool_->shared_bent;
    bent.assign(last->begin(), last->begin() + static_cast<std::ptrdiff_t>(same));
  }
  if (bent.size() == f.deformable.size()) return nullptr;
  tool_->shared_bent = std::make_shared<const IndexList>(std::move(bent));
  return tool_->shared_bent;
}

SessionImage EditSession::capture_rows(const IndexList& rows, bool subset, bool detector,
                                       std::shared_ptr<const IndexList> bent, Points* previous) {
  SessionImage image;
  RowsImage r = history_.take_spare();
  // The row list is shared while it does not change (the deformable rows, step after step).
  if (!tool_->shared_rows || *tool_->shared_rows != rows) tool_->shared_rows = std::make_shared<const IndexList>(rows);
  r.rows = tool_->shared_rows;
  r.bent = std::move(bent);
  const IndexList& turned = r.bent ? *r.bent : rows;  // rows whose normals and tangents are kept
  const SurfelArrays& a = model_.arrays();
  std::vector<detail::RowCopy> copies;
  take_rows(a.positions, rows, r.positions, copies, previous ? previous->data() : nullptr);
  take_rows(a.normals, turned, r.normals, copies);
  static const Points none(0, 3);  // (both branches lvalues: no copy of the model's tangents)
  take_rows(model_.has_tangents() ? a.tangent_u : none, turned, r.tangent_u, copies);
  take_rows(model_.has_tangents() ? a.tangent_v : none, turned, r.tangent_v, copies);
  detail::run_row_copies(copies, resolve_threads(params_.threads));
  // Runs of equal versions along `rows`, each counted in a local (an increment of the run in memory made every row
  // wait on the last one's store: RESULTS §71).
  r.version_runs.clear();
  for (std::size_t i = 0; i < rows.size();) {
    const std::uint64_t v = row_version_[static_cast<std::size_t>(rows[i])];
    std::size_t j = i + 1;
    while (j < rows.size() && row_version_[static_cast<std::size_t>(rows[j])] == v) ++j;
    r.version_runs.emplace_back(v, static_cast<std::uint32_t>(j - i));
    i = j;
  }
  image.rows = std::move(r);
  image.tool = tool_id_;
  image.detector_object = tool_->detector;
  image.stale = tool_->stale;
  if (tool_->detector && detector) {
    image.detector = tool_->detector->save_image(subset ? &rows : nullptr);
    image.complete = image.detector != nullptr;
  }
  image.colliding = tool_->colliding;
  image.steps = tool_->steps;
  return image;
}

SessionImage EditSession::whole_before_step(const SessionImage& before) const {
  SessionImage image;
  WholeImage w;
  w.model = model_;
  put_image_rows(w.model.arrays(), *before.rows);
  const RowsImage& r = *before.rows;
  w.model_version = model_version_;
  w.row_version = row_version_;
  put_versions(w.row_version, *r.rows, r.version_runs);
  w.rest_radius = rest_radius_;
  w.history = history_params_;
  for (const auto& [id, t] : tools_) w.tools.emplace(id, t.image(false));
  // The acting tool's detector is the live one: the caller puts its state back once it is no longer live.
  ToolImage& own = w.tools.at(tool_id_);
  own.colliding = before.colliding;
  own.steps = before.steps;
  own.stale = before.stale;
  image.whole = std::move(w);
  image.tool = tool_id_;
  return image;
}

std::shared_ptr<const DetectorImage> EditSession::step_detector_image(const SessionImage& before) const {
  return tool_->journaling ? tool_->detector->journal_image() : before.detector;
}

SessionImage EditSession::capture_whole(bool clone) {
  SessionImage image;
  WholeImage w;
  w.model = model_;
  w.model_version = model_version_;
  w.row_version = row_version_;
  w.rest_radius = rest_radius_;
  w.history = history_params_;
  // Only the acting tool's detector may change in place during the op (others are never changed by it).
  for (const auto& [id, t] : tools_) w.tools.emplace(id, t.image(false));
  if (clone && tool_->detector) {
    std::shared_ptr<CollisionDetector> copy(tool_->detector->clone());
    image.complete = copy != nullptr;
    if (copy) tool_->detector = std::move(copy);
  }
  image.whole = std::move(w);
  image.tool = tool_id_;
  return image;
}

SessionImage EditSession::capture_tool(bool keep_fields) {
  SessionImage image;
  ToolOnlyImage o;
  o.tool = tool_->image(false);
  if (keep_fields) {
    o.tool.fields.reset();
    o.tool.fields_kept = true;
  }
  // A detector (and merge origins) as a reset from this very model made them: re-derived on restore.
  if (tool_->detector_fresh(version_)) {
    o.tool.detector.reset();
    o.tool.merge.origin_positions.resize(0, 3);
    o.tool.merge.origin_normals.resize(0, 3);
    o.tool.merge.origins_in_detector = false;
    o.tool.derive_detector = true;
  }
  o.history = history_params_;
  image.tool_only = std::move(o);
  image.tool = tool_id_;
  return image;
}

void EditSession::restore_tool(Tool& t, const ToolImage& image, bool clone) {
  t.restore(image, clone);
  if (!image.derive_detector || !t.fields || model_.empty()) return;
  t.detector = fresh_detector(t.settings, *t.fields);
  Tool* acting = tool_;
  tool_ = &t;
  take_origins();
  tool_ = acting;
}

void EditSession::restore(const SessionImage& image, bool clone) {
  if (!image.complete) throw Error(ErrorCode::Internal, "history", "the image holds no detector state");
  Tool& t = use(image.tool);
  if (image.rows) {
    const RowsImage& r = *image.rows;
    put_image_rows(model_.arrays(), r);
    put_versions(row_version_, *r.rows, r.version_runs);
    // The detector object the states belong to (the tool may have re-initialised its detector since).
    t.detector = image.detector_object;
    t.clear_stale();  // the rows moved since are not in the image: a stale tool is re-initialised
    if (image.stale) t.mark_stale(nullptr);
    // A step's image without detector states while the journal runs: the journal holds them.
    if (image.detector) t.detector->restore_image(*image.detector);
    else if (t.detector && t.journaling) t.detector->restore_journal();
    t.colliding = image.colliding;
    t.steps = image.steps;
    t.fresh_at = 0;
  } else if (image.tool_only) {
    history_params_ = image.tool_only->history;
    restore_tool(t, image.tool_only->tool, clone);
  } else {
    const WholeImage& w = *image.whole;
    model_ = w.model;
    model_version_ = w.model_version;
    row_version_ = w.row_version;
    rest_radius_ = w.rest_radius;
    history_params_ = w.history;
    // Tools made after the image (by use()) hold nothing the image's op could have seen: kept as they are.
    for (const auto& [id, ti] : w.tools) tools_[id].restore(ti, clone && id == image.tool);
  }
}

std::size_t EditSession::history_limit() const {
  return static_cast<std::size_t>(history_params_.history_mb * 1024.0 * 1024.0);
}

void EditSession::record(const char* op, const std::string& author, IdList touched, SessionImage before,
                         const IndexList* moved) {
  record_shared(op, author, shared_ascending(std::move(touched)), std::move(before), moved);
}

void EditSession::record_shared(const char* op, const std::string& author, std::shared_ptr<const IdList> touched,
                                SessionImage before, const IndexList* moved) {
  HistoryEntry e;
  e.item = {version_, op, author, {}, false};
  e.touched = std::move(touched);
  e.image = std::make_shared<SessionImage>(std::move(before));
  if (!e.touched->empty()) mark_others_stale(moved);
  history_.push(std::move(e), history_limit());
}

std::shared_ptr<const IdList> EditSession::step_touched(const IndexList& moved) {
  const std::shared_ptr<const IdList>& last = tool_->shared_touched;
  if (last && last->size() == moved.size()) {
    // Equal in row order means the ids in row order are ascending and unique, as `last` is.
    bool same = true;
    for (std::size_t k = 0; k < moved.size(); ++k) same &= (*last)[k] == model_.id_of(moved[k]);
    if (same) return last;
  }
  IdList ids;
  ids.reserve(moved.size());
  for (const Index r : moved) ids.push_back(model_.id_of(r));
  tool_->shared_touched = shared_ascending(std::move(ids));
  return tool_->shared_touched;
}

std::uint64_t EditSession::swap_entry(HistoryEntry& entry, const char* what) {
  if (!entry.image->complete) {
    throw Error(ErrorCode::Conflict, "history",
                std::string("cannot ") + what + " '" + entry.item.op +
                    "': its detector state was not saved (hierarchies and approximate detection keep no history)");
  }
  use(entry.image->tool);
  // The rows image of the other side keeps what this one keeps (the step changed no other normals).
  SessionImage now = entry.image->rows        ? capture_rows(*entry.image->rows->rows, false, true, entry.image->rows->bent)
                     : entry.image->tool_only ? capture_tool(entry.image->tool_only->tool.fields_kept)
                                             : capture_whole(false);
  const IdList ids_before = model_.ids();
  if (entry.image->rows) hold_for_others(*entry.image->rows->rows);  // they move under the other tools' detectors
  restore(*entry.image, false);
  // A step's rows moved under the other tools' detectors (a whole image puts every tool back as it was).
  if (entry.image->rows) mark_others_stale(entry.image->rows->rows.get());
  history_.replace_image(entry, std::move(now));
  // The restored rows count as changed now; ids that went away are logged as removed.
  ++version_;
  if (entry.item.op == "load") model_version_ = version_;
  std::unordered_set<SurfelId> touched(entry.touched->begin(), entry.touched->end());
  const IdList& ids = model_.ids();
  for (std::size_t r = 0; r < ids.size(); ++r)
    if (touched.count(ids[r])) row_version_.set(r, version_);
  for (SurfelId id : ids_before)
    if (model_.row_of(id) < 0) removed_log_.emplace_back(version_, id);
  return version_;
}

namespace {

bool meet(const IdList& a, const IdList& b) {  // both ascending
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i == *j) return true;
    if (*i < *j) ++i;
    else ++j;
  }
  return false;
}

// An entry whose op inserted or removed surfels (a whole image with touched surfels): rows renumbered.
bool renumbers(const HistoryEntry& e) { return e.image->whole && !e.touched->empty(); }

// Whether another author's entry `o` is in effect now and was not at `e`'s last swap, or the other way
// round: applied or redone since, or in effect then and undone since. (Applied and undone again since
// leaves the surfels as they were; an undo is exact on what it touched.)
bool changed_since(const HistoryEntry& o, const HistoryEntry& e) {
  if (&o == &e || o.item.author == e.item.author || o.stamp <= e.stamp) return false;
  return !o.item.undone || o.applied_at < e.stamp;
}

}  // namespace

std::uint64_t EditSession::swap_own(HistoryEntry& e, bool undo) {
  const char* what = undo ? "undo" : "redo";
  const auto& entries = history_.entries();
  // Whole: no other author's entry changed state since this one's last swap (changed_since), so the
  // session is exactly as it left it but for the author's own later entries, all undone (last in, first
  // out per author). A single author's history is always this case, and so is undo() in strict global
  // order.
  bool whole = true;
  for (const HistoryEntry& o : entries)
    if (changed_since(o, e)) whole = false;
  if (!whole) {
    for (const HistoryEntry& o : entries) {
      if (!changed_since(o, e)) continue;
      const bool hit = renumbers(o) || renumbers(e) || meet(*o.touched, *e.touched);
      if (!hit) continue;
      std::string why = renumbers(e) ? "it inserted or removed surfels and cannot come back alone"
                        : renumbers(o) ? "that op inserted or removed surfels since"
                                       : "that op changed surfels it changed since";
      throw Error(ErrorCode::Conflict, "history",
                  std::string("cannot ") + what + " '" + e.item.op + "' (version " + std::to_string(e.item.version) +
                      ") of client '" + e.item.author + "': client '" + o.item.author + "' " +
                      (o.item.undone ? "undid" : "applied") + " '" + o.item.op + "' (version " +
                      std::to_string(o.item.version) + ") after it; " + why);
    }
  }
  if (!e.image->complete) {
    throw Error(ErrorCode::Conflict, "history",
                std::string("cannot ") + what + " '" + e.item.op +
                    "': its detector state was not saved (hierarchies and approximate detection keep no history)");
  }
  std::uint64_t v = 0;
  if (whole || e.image->rows) {
    v = swap_entry(e, what);
    // Its tool's detector saw the rows other tools moved since as they were then.
    if (!whole) tools_.at(e.image->tool).mark_stale(nullptr);
  } else {
    // A change of the author's tool alone (set_regions, configure, release): that tool comes back.
    // (A whole image without touched surfels, e.g. a resampling step that moved nothing: its tool alone.)
    const ToolImage& t = e.image->tool_only ? e.image->tool_only->tool : e.image->whole->tools.at(e.image->tool);
    if (t.fields && t.fields->regions.size() != static_cast<std::size_t>(model_.size()))
      throw Error(ErrorCode::Internal, "history", "the tool image does not fit the model");
    for (const auto& [id, other] : tools_) {
      if (id == e.image->tool || !other.fields || !t.fields) continue;
      const std::size_t overlap = lock_overlap(t.fields->regions, other.fields->regions);
      if (overlap > 0) {
        throw Error(ErrorCode::Conflict, "history",
                    std::string("cannot ") + what + " '" + e.item.op + "' of client '" + e.item.author + "': " +
                        std::to_string(overlap) + " surfel(s) of its regions are in the lock of client '" + id + "'");
      }
    }
    use(e.image->tool);
    SessionImage now = e.image->tool_only ? capture_tool(t.fields_kept) : capture_whole(false);
    restore_tool(*tool_, t, false);
    tool_->mark_stale(nullptr);
    history_.replace_image(e, std::move(now));
    v = ++version_;
  }
  history_.set_undone(e, undo, v);
  return v;
}

std::uint64_t EditSession::undo() {
  HistoryEntry* e = history_.last_applied();
  if (!e) throw Error(ErrorCode::Conflict, "history", "nothing to undo in session '" + name_ + "'");
  return swap_own(*e, true);
}

std::uint64_t EditSession::redo() {
  HistoryEntry* e = history_.last_undone();
  if (!e) throw Error(ErrorCode::Conflict, "history", "nothing to redo in session '" + name_ + "'");
  return swap_own(*e, false);
}

std::uint64_t EditSession::undo(const std::string& author) {
  HistoryEntry* e = history_.undo_target(author);
  if (!e) {
    throw Error(ErrorCode::Conflict, "history",
                "nothing of client '" + author + "' to undo in session '" + name_ + "'");
  }
  return swap_own(*e, true);
}

std::uint64_t EditSession::redo(const std::string& author) {
  HistoryEntry* e = history_.redo_target(author);
  if (!e) {
    throw Error(ErrorCode::Conflict, "history",
                "nothing of client '" + author + "' to redo in session '" + name_ + "'");
  }
  return swap_own(*e, false);
}

}  // namespace surfeledit
