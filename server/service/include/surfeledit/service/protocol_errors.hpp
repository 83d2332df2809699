// The core's errors in the protocol's terms: a reply's status, message and field.
#pragma once

#include <string>

#include "surfeledit/core/types.hpp"
#include "surfeledit/service/reply.hpp"

namespace surfeledit::service {

// Protocol status of a core error code (same numbers).
Status status_of(ErrorCode code);

// The message of a core error without the "field: " prefix of what().
std::string message_of(const Error& e);
// Re-throws `e` with "<prefix>." in front of its field (unless it already starts with it),
// so that core field names ("axis") become protocol field names ("deform.axis").
[[noreturn]] void rethrow_prefixed(const Error& e, const std::string& prefix);

}  // namespace surfeledit::service
