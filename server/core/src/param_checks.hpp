// Validation of the particle, blend and hole-filling parameters (private to the core): one message format,
// "field = value: must be rule".
#pragma once

#include <cmath>
#include <string>

#include "surfeledit/core/types.hpp"

namespace surfeledit::param_checks {

// Throws InvalidArgument naming `field` ("field = value: must be rule") unless `ok` holds and `value` is not NaN.
inline void require(bool ok, const char* field, double value, const char* rule) {
  if (!ok || std::isnan(value))
    throw Error(ErrorCode::InvalidArgument, field,
                std::string(field) + " = " + std::to_string(value) + ": must be " + rule);
}

// As require(), and refuses infinite values too.
inline void require_finite(bool ok, const char* field, double value, const char* rule) {
  require(ok && std::isfinite(value), field, value, rule);
}

}  // namespace surfeledit::param_checks
