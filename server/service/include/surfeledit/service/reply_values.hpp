// The core's results in the reply's form (reply.hpp): settings, step results, collision stats.
#pragma once

#include <cstdint>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/service/reply.hpp"

namespace surfeledit::service {

// A core setting in the reply's form (kind from the value's type).
Setting to_reply(const NamedSetting& s);
// A core step result in the reply's form, as step number `seq`. Throws std::logic_error when its
// depths do not match its colliding ids.
StepResult to_reply(const surfeledit::StepResult& result, std::uint64_t seq);
// Every counter of the core's collision stats.
CollisionStatsInfo to_reply(const CollisionStats& stats);

}  // namespace surfeledit::service
