#include "surfeledit/core/edit_session.hpp"

#include <algorithm>
#include <sstream>

namespace surfeledit {

EditSession::EditSession(std::string name, SessionParams params)
    : name_(std::move(name)), params_(params) {}

EditSession::~EditSession() = default;

const SurfelModel& EditSession::model() const {
  if (model_.empty()) throw Error(ErrorCode::Conflict, "session", "no model loaded in session '" + name_ + "'");
  return model_;
}

void EditSession::load(SurfelModel model) {
  if (model.empty()) throw Error(ErrorCode::InvalidArgument, "positions", "the model is empty (0 surfels)");
  ++version_;
  model_ = std::move(model);
  model_version_ = version_;
  row_version_.assign(static_cast<std::size_t>(model_.size()), version_);
  removed_log_.clear();
  fields_.reset();
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
    if (chosen[r]) ids.push_back(m.ids()[r]);
  return ids;
}

void EditSession::set_regions(const RegionSpec& zero, const RegionSpec& one) {
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
  auto fields = std::make_unique<DeformationFields>(compute_fields(model_.positions(), regions, params_.threads));
  fields_ = std::move(fields);
  ++version_;
}

StepOutcome EditSession::deform(const DeformParams& params) {
  model();  // throws without a model
  if (!fields_) throw Error(ErrorCode::Conflict, "regions", "set the zero and one regions before deforming");
  SurfelArrays& a = model_.arrays();
  const bool tangents = model_.has_tangents();
  const DeformResult r = apply_step(*fields_, params, a.positions, a.normals, tangents ? &a.tangent_u : nullptr,
                                    tangents ? &a.tangent_v : nullptr, params_.threads);
  ++version_;
  touch_rows(r.moved);
  StepOutcome out;
  out.seq = ++steps_;
  out.moved = r.moved;
  out.center = r.center;
  return out;
}

void EditSession::configure(const std::vector<NamedSetting>&) {
  throw Error(ErrorCode::Internal, "configure", "collision settings are not available in this build yet");
}

void EditSession::remove(const IdList&) {
  throw Error(ErrorCode::Internal, "remove", "surfel removal is not available in this build yet");
}

void EditSession::touch_rows(const IndexList& rows) {
  for (Index r : rows) row_version_[r] = version_;
}

Changes EditSession::changes_since(std::uint64_t since) const {
  Changes c;
  if (model_.empty() || since >= version_) return c;
  c.full = since < model_version_;
  const IdList& ids = model_.ids();
  for (std::size_t r = 0; r < ids.size(); ++r)
    if (c.full || row_version_[r] > since) c.changed.push_back(ids[r]);
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
  rep.structures.push_back({"versions", row_version_.size() * sizeof(std::uint64_t) +
                                            removed_log_.size() * sizeof(removed_log_[0])});
  if (fields_) rep.structures.push_back({"deformation_fields", fields_->memory_bytes()});
  for (const auto& s : rep.structures) rep.total_bytes += s.bytes;
  rep.bytes_per_surfel = rep.surfels ? static_cast<double>(rep.total_bytes) / rep.surfels : 0.0;
  return rep;
}

std::uint64_t EditSession::state_hash() const { return model_.empty() ? 0 : model_.hash(); }

}  // namespace surfeledit
