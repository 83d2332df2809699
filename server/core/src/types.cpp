#include "surfeledit/core/types.hpp"

#include <cmath>
#include <sstream>

namespace surfeledit {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument: return "invalid_argument";
    case ErrorCode::NotFound: return "not_found";
    case ErrorCode::Conflict: return "conflict";
    case ErrorCode::TooLarge: return "too_large";
    case ErrorCode::Io: return "io";
    case ErrorCode::Internal: return "internal";
  }
  return "unknown";
}

Error::Error(ErrorCode code, std::string field, const std::string& message)
    : std::runtime_error(field.empty() ? message : field + ": " + message),
      code_(code),
      field_(std::move(field)) {}

void require_finite(const double* data, Eigen::Index rows, Eigen::Index cols, const std::string& field) {
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < cols; ++c) {
      const double v = data[r * cols + c];
      if (!std::isfinite(v)) {
        std::ostringstream msg;
        msg << "non-finite value " << v << " at row " << r << ", column " << c;
        throw Error(ErrorCode::InvalidArgument, field, msg.str());
      }
    }
  }
}

}  // namespace surfeledit
