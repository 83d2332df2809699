#include "surfeledit/service/reply_values.hpp"

#include <stdexcept>
#include <variant>

namespace surfeledit::service {

Setting to_reply(const NamedSetting& s) {
  Setting out;
  out.name = s.name;
  if (const double* number = std::get_if<double>(&s.value)) {
    out.kind = SettingKind::Number;
    out.number = *number;
  } else if (const std::int64_t* integer = std::get_if<std::int64_t>(&s.value)) {
    out.kind = SettingKind::Int;
    out.number = static_cast<double>(*integer);
  } else if (const bool* flag = std::get_if<bool>(&s.value)) {
    out.kind = SettingKind::Bool;
    out.flag = *flag;
  } else {
    out.kind = SettingKind::Text;
    out.text = std::get<std::string>(s.value);
  }
  return out;
}

CollisionStatsInfo to_reply(const CollisionStats& cs) {
  CollisionStatsInfo out;
  out.deformable = static_cast<std::uint64_t>(cs.deformable);
  out.tested = static_cast<std::uint64_t>(cs.tested);
  out.queries = static_cast<std::uint64_t>(cs.queries);
  out.colliding = static_cast<std::uint64_t>(cs.colliding);
  out.detect_ms = cs.detect_ms;
  out.preprocess_ms = cs.preprocess_ms;
  out.nv = static_cast<std::uint64_t>(cs.nv);
  out.np = static_cast<std::uint64_t>(cs.np);
  out.nu = static_cast<std::uint64_t>(cs.nu);
  out.asleep = static_cast<std::uint64_t>(cs.asleep);
  return out;
}

StepResult to_reply(const surfeledit::StepResult& result, std::uint64_t seq) {
  StepResult step;
  step.seq = seq;
  step.moved = result.moved.size();
  step.center = {result.center.x(), result.center.y(), result.center.z()};
  step.detected = result.detected;
  if (result.depths.size() != result.colliding.size()) {
    throw std::logic_error("step outcome has " + std::to_string(result.depths.size()) + " depths for " +
                           std::to_string(result.colliding.size()) + " colliding ids");
  }
  step.colliding = result.colliding;
  step.depths = result.depths;
  step.stats = to_reply(result.stats);
  step.inserted = result.inserted;
  step.response = result.response;
  step.backoff_iterations = static_cast<std::uint32_t>(result.backoff.iterations);
  step.backoff_kept = result.backoff.kept;
  step.backoff_depth = result.backoff.final_depth;
  step.features = result.features;
  return step;
}

}  // namespace surfeledit::service
