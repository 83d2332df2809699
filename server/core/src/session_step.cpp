// The edit session's deform step (EditSession::deform and step_once): validation, the step, the collision
// response and roll back of a refused step; the rest of the session is in edit_session.cpp.
#include <algorithm>
#include <chrono>

#include "row_copy.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/resampling.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// The first k (in list order) whose row rows[k] has a non-finite position or normal after a step; rows.size()
// when none. Run only after a step whose kernel wrote a non-finite value (DeformResult::finite), to name the
// row. `flat` (the fields' regions, or null): the step had no rotation, so the normals of F1 rows are bit for
// bit what they were before it (deformation_kernel.hpp's flat path, as step_bent_rows relies on), and finite
// as the model's are: only their positions are read.
std::size_t first_non_finite(const SurfelArrays& a, const IndexList& rows, const std::vector<Region>* flat) {
  const double* P = a.positions.data();
  const double* N = a.normals.data();
  // x - x is 0 for every finite x and NaN for an infinite or NaN one: one test for three values.
  auto bad = [](const double* v) { return !((v[0] - v[0]) + (v[1] - v[1]) + (v[2] - v[2]) == 0.0); };
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Index r = rows[k];
    if (bad(P + 3 * r)) return k;
    if ((!flat || (*flat)[static_cast<std::size_t>(r)] != Region::One) && bad(N + 3 * r)) return k;
  }
  return rows.size();
}

}  // namespace

StepResult EditSession::deform(const DeformParams& params, const std::string& author) {
  model();  // throws without a model
  const Tool* own = find_tool(author);
  if (!own || !own->fields) throw Error(ErrorCode::Conflict, "regions", "set the zero and one regions before deforming");
  validate(params, *own->fields);
  use(author);
  tool_->fresh_at = 0;  // a step changes the detector (or may: a cancelled one puts its states back)
  sync_tool();
  hold_for_others(tool_->fields->deformable);  // the rows a step moves, as the other tools' detectors see them
  const std::uint64_t version_before = version_;
  const Index rows_before = model_.size();
  // Resampling may add tangents, rest radii and rows: the whole session is the before-image. Else the
  // deformable rows, and the detector states the step changes (its journal, when it keeps one); a merge
  // after the step (response "merge") upgrades it to a whole image (respond()).
  const auto t_capture = std::chrono::steady_clock::now();
  const bool whole = tool_->settings.resample.enabled;
  // Nothing is kept (history_mb 0) and nothing is taken back (response report): no image at all.
  const bool none = history_limit() == 0 && tool_->settings.response.mode == Response::Report;
  tool_->journaling = !whole && !none && tool_->detector && tool_->detector->start_journal();
  struct EndJournal {
    EditSession& s;
    ~EndJournal() {
      if (s.tool_->detector) s.tool_->detector->stop_journal();
      s.tool_->journaling = false;
    }
  } end_journal{*this};
  // The rows image's pass over the deformable positions also brings `previous` up to date when only they
  // differ (one read of the positions for both copies).
  const bool fuse_previous = !none && !whole && previous_current();
  SessionImage before = none    ? SessionImage()
                        : whole ? capture_whole(true)
                                : capture_rows(tool_->fields->deformable, false, !tool_->journaling, step_bent_rows(params),
                                               fuse_previous ? &tool_->previous : nullptr);
  const double capture_ms = ms_since(t_capture);
  StepResult out;
  try {
    step_once(params, out, fuse_previous);
    respond(params, before, version_before, out);
  } catch (...) {
    // All or nothing: a step that fails part-way (a detector or allocation failure) leaves the session
    // exactly as before it, version included.
    roll_back(before, version_before);
    throw;
  }
  // A step moves the tool's deformable rows only (rigid to every other tool); resampling's splits or a
  // merge change rows otherwise.
  const IndexList* moved = model_.size() == rows_before && out.response != "merged" ? &tool_->fields->deformable : nullptr;
  if (moved) tool_->previous_at = version_;  // `previous` differs from the model on deformable rows only
  if (version_ != version_before) mark_others_stale(moved);
  const auto t_record = std::chrono::steady_clock::now();
  if (tool_->journaling && before.rows) before.detector = tool_->detector->journal_image();
  if (out.response != "cancelled" && !none) {
    if (out.response == "merged") {
      IdList touched;
      touched.reserve(out.moved.size());
      for (Index r : out.moved) touched.push_back(model_.id_of(r));
      const IdList removed = changes_since(version_before).removed;
      touched.insert(touched.end(), removed.begin(), removed.end());
      record("deform", author, std::move(touched), std::move(before), moved);
    } else {
      record_shared("deform", author, step_touched(out.moved), std::move(before), moved);
    }
  }
  out.history_ms = capture_ms + ms_since(t_record);
  return out;
}

void EditSession::roll_back(SessionImage& before, std::uint64_t version_before) {
  const bool detector_saved = before.complete;
  before.complete = true;  // restore() puts back what the image holds; an unsaved detector is rebuilt below
  restore(before, true);
  before.complete = detector_saved;
  if (!detector_saved && tool_->fields && !model_.empty()) {
    tool_->own_origins();  // the merge origins stay those of the last reset
    tool_->detector = fresh_detector(tool_->settings, *tool_->fields);
  }
  while (!removed_log_.empty() && removed_log_.back().first > version_before) removed_log_.pop_back();
  version_ = version_before;
}

bool EditSession::previous_current() const {
  return tool_->detector && tool_->previous_at != 0 && tool_->previous_at == version_ &&
         tool_->previous.rows() == model_.arrays().positions.rows();
}

void EditSession::step_once(const DeformParams& params, StepResult& out, bool previous_done) {
  SurfelArrays& a = model_.arrays();
  const bool resample = tool_->settings.resample.enabled;
  if (resample) {
    // Tangent axes (kept up to date by apply_step) and rest radii, from when resampling started.
    if (!model_.has_tangents()) make_tangent_frames(a.normals, a.radii, a.tangent_u, a.tangent_v);
    if (rest_radius_.size() != model_.size()) rest_radius_ = a.radii;
  }
  Points& previous = tool_->previous;  // positions before the step, for each surfel's own displacement
  const bool from_last_step = tool_->previous_at != 0 && tool_->previous_at == version_ && previous.rows() == a.positions.rows();
  if (!tool_->detector) {
    previous.resize(0, 3);
  } else if (previous_done) {
    // deform() copied the deformable rows in the before-image's pass (previous_current() held).
  } else if (from_last_step) {
    // Nothing but this tool's last step changed the model since `previous` was taken: only the deformable
    // rows differ (at 1M surfels a whole copy is most of a millisecond per 300k rows it need not move).
    detail::run_row_copies({{a.positions.data(), &tool_->fields->deformable, previous.data(), true}},
                           resolve_threads(params_.threads));
  } else {
    previous = a.positions;  // same size as the last step's: no allocation
  }
  tool_->previous_at = 0;  // set again when the step completes (deform())
  const bool tangents = model_.has_tangents();
  out = StepResult();
  const auto t_deform = std::chrono::steady_clock::now();
  const DeformResult r = apply_step(*tool_->fields, params, a.positions, a.normals, tangents ? &a.tangent_u : nullptr,
                                    tangents ? &a.tangent_v : nullptr, params_.threads);
  out.deform_ms = ms_since(t_deform);
  // The bounds of validate(params, fields) keep a step finite on models of sane coordinates; anything
  // else is refused here, before the detector sees it (deform() then rolls the rows back).
  const std::size_t bad =
      r.finite ? r.moved.size() : first_non_finite(a, r.moved, params.angle == 0.0 ? &tool_->fields->regions : nullptr);
  if (bad < r.moved.size()) {
    throw Error(ErrorCode::InvalidArgument, "translation",
                "the step would move surfel " + std::to_string(model_.id_of(r.moved[bad])) + " to a non-finite position");
  }
  ++version_;
  touch_rows(r.moved);
  out.seq = ++tool_->steps;
  out.moved = r.moved;
  out.center = r.center;
  // Applies planned splits: the parent row becomes child A, child B is appended with a new id.
  auto apply_splits = [&](SplitPlan plan) {
    if (plan.parents.empty()) return;
    const Index old_rows = model_.size();
    const Eigen::Index k = static_cast<Eigen::Index>(plan.parents.size());
    const Values b_radii = plan.b.radii;
    out.inserted = model_.insert(std::move(plan.b));  // validates child B before anything else changes
    DeformationFields& f = *tool_->fields;
    const Index rows = old_rows + static_cast<Index>(k);
    extend_fields(f, plan.parents);  // child B inherits the parent's deformation fields
    rest_radius_.conservativeResize(rows);
    if (previous.rows() > 0) previous.conservativeResize(rows, 3);
    for (Eigen::Index j = 0; j < k; ++j) {
      const Index parent = plan.parents[static_cast<std::size_t>(j)];
      const Index child = old_rows + static_cast<Index>(j);
      // The parent row becomes child A.
      a.positions.row(parent) = plan.a.positions.row(j);
      a.normals.row(parent) = plan.a.normals.row(j).normalized();
      a.radii[parent] = plan.a.radii[j];
      a.tangent_u.row(parent) = plan.a.tangent_u.row(j);
      a.tangent_v.row(parent) = plan.a.tangent_v.row(j);
      if (plan.a.colors.rows() > 0 && a.colors.rows() == rows) a.colors.row(parent) = plan.a.colors.row(j);
      rest_radius_[parent] = plan.a.radii[j];
      rest_radius_[child] = b_radii[j];
      if (previous.rows() > 0) previous.row(child) = previous.row(parent);
      row_version_.push_back(version_);
      out.moved.push_back(child);
    }
    // Other tools' fields get the children too (Zero to them: the parents are in this tool's lock).
    for (auto& [id, t] : tools_)
      if (&t != tool_ && t.fields) extend_fields(*t.fields, plan.parents);
    if (tool_->detector) tool_->detector->on_inserted(scene_of(f), plan.parents);
  };
  if (resample) {
    const auto t_resample = std::chrono::steady_clock::now();
    apply_splits(plan_splits(a, r.moved, rest_radius_, tool_->settings.resample));
    out.resample_ms = ms_since(t_resample);
  }
  if (tool_->detector) {
    CollisionScene scene = scene_of(*tool_->fields);
    // Nothing but this step moved rows since the detector's last detect, and no split resized one: the
    // deformation's own bound spares the detector its pass over the rows (CollisionScene::displacement_bound).
    if (from_last_step && out.inserted.empty()) scene.displacement_bound = displacement_bound(params);
    CollisionResult c = tool_->detector->detect(scene, previous);
    out.detected = true;
    out.colliding.reserve(c.colliding.size());
    for (Index row : c.colliding) out.colliding.push_back(model_.id_of(row));
    out.depths = std::move(c.depths);
    out.stats = c.stats;
    tool_->colliding = out.colliding;
  }
}

}  // namespace surfeledit
