// The session's tools (docs/collaboration.md): one per author, each with its settings, fields, detector
// and colliding set; a tool whose rows another tool moved is stale until sync_tool() brings its detector up
// to date (on_rigid_moved with the rows' held old values, or a fresh detector).
#include <algorithm>
#include <iterator>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

Tool& EditSession::use(const std::string& author) {
  auto [it, created] = tools_.try_emplace(author);
  if (created) it->second.settings = new_settings();
  tool_ = &it->second;
  tool_id_ = author;
  return *tool_;
}

const Tool* EditSession::find_tool(const std::string& author) const {
  const auto it = tools_.find(author);
  return it == tools_.end() ? nullptr : &it->second;
}

SessionSettings EditSession::settings_of(const std::string& author) const {
  const Tool* t = find_tool(author);
  SessionSettings s = t ? t->settings : new_settings();
  s.history = history_params_;
  return s;
}

SessionSettings EditSession::new_settings() const {
  SessionSettings s;
  s.history = history_params_;
  s.collision.threads = std::min(params_.threads, hardware_threads());
  return s;
}

SessionSettings EditSession::settings(const std::string& tool) const { return settings_of(tool); }

const DeformationFields* EditSession::fields(const std::string& tool) const {
  const Tool* t = find_tool(tool);
  return t ? t->fields.get() : nullptr;
}

const IdList& EditSession::colliding(const std::string& tool) const {
  static const IdList none;
  const Tool* t = find_tool(tool);
  return t ? t->colliding : none;
}

std::vector<std::pair<std::string, Index>> EditSession::tools() const {
  std::vector<std::pair<std::string, Index>> out;
  for (const auto& [id, t] : tools_)
    if (t.fields) out.emplace_back(id, static_cast<Index>(t.fields->deformable.size()));
  return out;
}

void EditSession::mark_others_stale(const IndexList* moved) {
  for (auto& [id, t] : tools_)
    if (&t != tool_ && t.fields) t.mark_stale(moved);
}

void EditSession::hold_for_others(const IndexList& rows) {
  if (!params_.incremental_rigid) return;
  for (auto& [id, t] : tools_)
    if (&t != tool_) t.hold_rigid(model_, rows);
}

void EditSession::sync_tool() {
  Tool& t = *tool_;
  if (!t.stale) return;
  // Rows this tool treats as rigid changed under its detector (another tool's op). Moved rows only: the
  // detector updates its structures for them (on_rigid_moved), told where they were (Tool::held, kept by
  // hold_for_others before each op that moved them). History images refer to the detector object and must
  // keep it as it was, so a shared detector is cloned first (a detector that cannot be cloned is reset instead).
  bool followed = false;
  RigidRows before;
  if (params_.incremental_rigid && t.fields && t.detector && t.stale_rows_known &&
      t.fields->regions.size() == static_cast<std::size_t>(model_.size()) && t.held_before(before)) {
    const bool shared = t.detector.use_count() > 1;
    std::shared_ptr<CollisionDetector> d = shared ? std::shared_ptr<CollisionDetector>(t.detector->clone()) : t.detector;
    if (d && d->on_rigid_moved(scene_of(*t.fields), t.stale_rows, before)) {
      t.detector = std::move(d);
      followed = true;
    }
  }
  // Otherwise it starts again from the model as it is now (the zero region where it is now; Robust's
  // original model is now).
  if (!followed) {
    t.own_origins();  // the merge origins stay those of the last reset
    if (t.fields) t.detector = fresh_detector(t.settings, *t.fields);
    t.colliding.clear();
  }
  t.clear_stale();
}

void EditSession::configure(const std::vector<NamedSetting>& changes, const std::string& author) {
  const SessionSettings next = apply_settings(settings_of(author), changes);
  const Tool* own = find_tool(author);
  std::shared_ptr<CollisionDetector> detector;
  if (own && own->fields && !model_.empty()) detector = fresh_detector(next, *own->fields);
  use(author);
  SessionImage before = capture_tool(true);
  tool_->settings = next;
  history_params_ = next.history;
  tool_->detector = std::move(detector);
  tool_->colliding.clear();
  tool_->clear_stale();
  if (tool_->fields) take_origins();
  tool_->mark_fresh(version_);
  record("configure", author, {}, std::move(before));
}

bool EditSession::rebuild_hierarchies(const std::string& tool) {
  Tool* t = tools_.count(tool) ? &tools_.at(tool) : nullptr;
  // A stale detector is re-initialised at the tool's next step anyway.
  if (!t || !t->detector || !t->fields || t->stale) return false;
  t->fresh_at = 0;  // the rebuilt tree may be adopted at the next step
  return t->detector->start_rebuild(scene_of(*t->fields));
}

HierarchyInfo EditSession::hierarchy_info(const std::string& tool) const {
  const Tool* t = find_tool(tool);
  return t && t->detector ? t->detector->hierarchy_info() : HierarchyInfo{};
}

bool EditSession::release(const std::string& author) {
  const Tool* own = find_tool(author);
  if (!own || !own->fields) return false;
  use(author);
  SessionImage before = capture_tool(false);
  tool_->clear_regions();
  ++version_;
  record("release", author, {}, std::move(before));
  return true;
}

std::shared_ptr<CollisionDetector> EditSession::fresh_detector(const SessionSettings& settings,
                                                               const DeformationFields& fields) const {
  std::unique_ptr<CollisionDetector> d = make_detector(settings);
  if (d) d->reset(scene_of(fields));
  return d;
}

}  // namespace surfeledit
