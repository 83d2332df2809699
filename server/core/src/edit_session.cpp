#include "surfeledit/core/edit_session.hpp"

#include <algorithm>
#include <iterator>
#include <sstream>

#include "surfeledit/core/resampling.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

EditSession::EditSession(std::string name, SessionParams params)
    : name_(std::move(name)), params_(params) {
  if (params_.threads < 0 || params_.threads > kMaxSessionThreads)
    throw Error(ErrorCode::InvalidArgument, "threads",
                "must be in 0.." + std::to_string(kMaxSessionThreads) + ", got " + std::to_string(params_.threads));
  use("");
}

void EditSession::check_unlocked(const std::vector<bool>* keep, const IndexList* parents, const char* field) const {
  for (const auto& [id, t] : tools_) {
    if (&t == tool_ || !t.fields) continue;
    std::size_t hit = 0;
    if (keep)
      for (std::size_t r = 0; r < keep->size(); ++r) hit += !(*keep)[r] && t.fields->regions[r] != Region::Zero;
    if (parents)
      for (Index r : *parents) hit += t.fields->regions[static_cast<std::size_t>(r)] != Region::Zero;
    if (hit > 0) {
      throw Error(ErrorCode::Conflict, field,
                  std::to_string(hit) + " surfel(s) are in the lock of client '" + id +
                      "' (its deformable region); it must release them first");
    }
  }
}

EditSession::~EditSession() = default;

const SurfelModel& EditSession::model() const {
  if (model_.empty()) throw Error(ErrorCode::Conflict, "session", "no model loaded in session '" + name_ + "'");
  return model_;
}

void EditSession::load(SurfelModel model, const std::string& author) {
  if (model.empty()) throw Error(ErrorCode::InvalidArgument, "positions", "the model is empty (0 surfels)");
  use(author);
  SessionImage before = capture_whole(false);
  IdList touched = model_.ids();
  const IdList incoming = model.ids();
  touched.insert(touched.end(), incoming.begin(), incoming.end());
  ++version_;
  model_ = std::move(model);
  model_version_ = version_;
  row_version_.assign(static_cast<std::size_t>(model_.size()), version_);
  removed_log_.clear();
  for (auto& [id, t] : tools_) t.clear_regions();
  rest_radius_ = Values();
  record("load", author, std::move(touched), std::move(before));
}

IdList EditSession::resolve(const RegionSpec& spec, const std::string& field) const {
  const SurfelModel& m = model();
  for (std::size_t k = 0; k < spec.selectors.size(); ++k) {
    validate(spec.selectors[k], field + ".selectors[" + std::to_string(k) + "]");
  }
  std::vector<bool> chosen(static_cast<std::size_t>(m.size()), false);
  for (Index r : m.rows_of(spec.ids, field + ".ids")) chosen[r] = true;
  for (const Selector& s : spec.selectors) {
    for (Index r : select_rows(m.positions(), s)) chosen[r] = true;
  }
  IdList ids;
  for (std::size_t r = 0; r < chosen.size(); ++r)
    if (chosen[r]) ids.push_back(m.id_of(r));
  return ids;
}

void EditSession::set_regions(const RegionSpec& zero, const RegionSpec& one, const std::string& author) {
  const IdList zero_ids = resolve(zero, "zero");
  const IdList one_ids = resolve(one, "one");
  if (zero_ids.empty()) throw Error(ErrorCode::InvalidArgument, "zero", "the zero region selects no surfel");
  if (one_ids.empty()) throw Error(ErrorCode::InvalidArgument, "one", "the one region selects no surfel");
  std::vector<Region> regions(static_cast<std::size_t>(model_.size()), Region::Blend);
  for (SurfelId id : zero_ids) regions[model_.row_of(id)] = Region::Zero;
  for (SurfelId id : one_ids) {
    Region& r = regions[model_.row_of(id)];
    if (r == Region::Zero) {
      std::ostringstream msg;
      msg << "surfel id " << id << " is in both the zero and the one region";
      throw Error(ErrorCode::Conflict, "one", msg.str());
    }
    r = Region::One;
  }
  // The lock: the new deformable rows may not meet another tool's.
  for (const auto& [id, t] : tools_) {
    if (id == author || !t.fields) continue;
    const std::size_t overlap = lock_overlap(regions, t.fields->regions);
    if (overlap > 0) {
      throw Error(ErrorCode::Conflict, "regions",
                  std::to_string(overlap) + " surfel(s) of the deformable region (outside zero) are in the lock of client '" +
                      id + "' (its deformable region); put them in the zero region or let it release them");
    }
  }
  auto fields = std::make_unique<DeformationFields>(compute_fields(model_.positions(), regions, params_.threads));
  std::shared_ptr<CollisionDetector> detector = fresh_detector(settings_of(author), *fields);
  use(author);
  SessionImage before = capture_tool(false);
  tool_->fields = std::move(fields);
  tool_->detector = std::move(detector);
  tool_->colliding.clear();
  tool_->clear_stale();
  take_origins();
  ++version_;
  tool_->mark_fresh(version_);
  record("set_regions", author, {}, std::move(before));
}

void EditSession::remove(const IdList& ids, const std::string& author) {
  const SurfelModel& m = model();
  const IndexList rows = m.rows_of(ids, "ids");  // NotFound / repeated ids
  if (rows.empty()) return;
  if (rows.size() == static_cast<std::size_t>(m.size())) {
    throw Error(ErrorCode::Conflict, "ids", "removing every surfel would leave an empty model");
  }
  std::vector<bool> keep(static_cast<std::size_t>(m.size()), true);
  for (Index r : rows) keep[r] = false;
  use(author);
  check_regions_kept(keep, "ids");
  check_unlocked(&keep, nullptr, "ids");
  SessionImage before = capture_whole(true);
  ++version_;
  remove_rows(ids, keep);
  if (tool_->detector) tool_->detector->on_removed(keep);
  IdList gone = ids;
  std::sort(gone.begin(), gone.end());
  IdList still;
  std::set_difference(tool_->colliding.begin(), tool_->colliding.end(), gone.begin(), gone.end(), std::back_inserter(still));
  tool_->colliding = std::move(still);
  record("remove", author, ids, std::move(before));
}

void EditSession::remove_rows(const IdList& ids, const std::vector<bool>& keep) {
  for (std::size_t r = 0; r < keep.size(); ++r)
    if (!keep[r]) removed_log_.emplace_back(version_, model_.id_of(r));
  model_.remove(ids);
  row_version_.compact(keep);
  if (rest_radius_.size() > 0) {
    Eigen::Index j = 0;
    for (Eigen::Index i = 0; i < rest_radius_.size(); ++i)
      if (keep[static_cast<std::size_t>(i)]) rest_radius_[j++] = rest_radius_[i];
    rest_radius_.conservativeResize(j);
  }
  for (auto& [id, t] : tools_)
    if (t.fields) compact_fields(*t.fields, keep);
}

void EditSession::check_regions_kept(const std::vector<bool>& keep, const char* field) const {
  for (const auto& [id, t] : tools_) {
    if (!t.fields) continue;
    std::size_t zero_left = 0, one_left = 0;
    for (std::size_t r = 0; r < keep.size(); ++r) {
      if (!keep[r]) continue;
      zero_left += t.fields->regions[r] == Region::Zero;
      one_left += t.fields->regions[r] == Region::One;
    }
    const std::string whose = &t == tool_ ? "" : " of client '" + id + "'";
    if (zero_left == 0) throw Error(ErrorCode::Conflict, field, "the removal would leave the zero region" + whose + " empty");
    if (one_left == 0) throw Error(ErrorCode::Conflict, field, "the removal would leave the one region" + whose + " empty");
  }
}

void EditSession::touch_rows(const IndexList& rows) {
  for (Index r : rows) row_version_.set(static_cast<std::size_t>(r), version_);
}

Changes EditSession::changes_since(std::uint64_t since, bool rows) const {
  Changes c;
  if (model_.empty() || since >= version_) return c;
  c.full = since < model_version_ || since < row_version_.floor();  // below the floor: not known exactly
  if (rows && c.full) return c;  // every row: none listed
  for (Index r = 0; r < model_.size(); ++r) {
    if (!c.full && row_version_[r] <= since) continue;
    if (rows) c.rows.push_back(r);
    else c.changed.push_back(model_.id_of(r));
  }
  if (!c.full) {
    for (const auto& [v, id] : removed_log_)
      if (v > since) c.removed.push_back(id);
  }
  return c;
}

SessionReport EditSession::report() const {
  SessionReport rep;
  rep.surfels = model_.size();
  rep.structures.push_back({"model", model_.memory_bytes()});
  rep.structures.push_back({"versions", row_version_.memory_bytes() +
                                            removed_log_.size() * sizeof(removed_log_[0])});
  // Every tool's (one entry per structure and tool; a single tool lists exactly what a session without tools did).
  for (const auto& [id, t] : tools_) {
    if (t.fields) rep.structures.push_back({"deformation_fields", t.fields->memory_bytes()});
    if (t.detector) {
      for (auto& [name, bytes] : t.detector->structures()) rep.structures.push_back({name, bytes});
      if (rep.hierarchy_status.empty()) rep.hierarchy_status = t.detector->hierarchy_info().status;
    }
    // What it keeps of rows another tool moved since its detector last saw them (Tool::hold_rigid).
    const std::size_t held = static_cast<std::size_t>(t.held.positions.size() + t.held.normals.size() + t.held.radii.size());
    if (held > 0) rep.structures.push_back({"rigid_held", held * sizeof(double) + t.held_rows.capacity() * sizeof(Index)});
    const std::size_t origins = static_cast<std::size_t>(t.merge.origin_positions.size() + t.merge.origin_normals.size());
    if (origins > 0) rep.structures.push_back({"merge_origins", origins * sizeof(double)});
    if (t.previous.size() > 0) {
      rep.structures.push_back({"step_scratch", static_cast<std::size_t>(t.previous.size()) * sizeof(double)});
    }
  }
  if (rest_radius_.size() > 0) {
    rep.structures.push_back({"resampling", static_cast<std::size_t>(rest_radius_.size()) * sizeof(double)});
  }
  rep.structures.push_back({"history", history_.bytes()});
  for (const char* kind : {"rows", "tool", "whole"}) rep.history_kinds.push_back({kind, 0, 0});
  for (const HistoryEntry& e : history_.entries()) {
    for (auto& k : rep.history_kinds) {
      if (k.kind != e.image->kind()) continue;
      ++k.entries;
      k.bytes += e.bytes;
    }
  }
  // Detector objects only the history keeps alive (history.hpp): "entries" counts the objects.
  const History::Held held = history_.held_detectors();
  rep.history_kinds.push_back({"detectors", held.objects, held.bytes});
  for (const auto& s : rep.structures) rep.total_bytes += s.bytes;
  rep.bytes_per_surfel = rep.surfels ? static_cast<double>(rep.total_bytes) / rep.surfels : 0.0;
  return rep;
}

std::uint64_t EditSession::state_hash() const { return model_.empty() ? 0 : model_.hash(); }

}  // namespace surfeledit
