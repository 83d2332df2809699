// Argument checks shared by the deformation fields (deformation.cpp) and the step (deformation_step.cpp):
// numbers in error messages with all 17 digits, thread counts, blend kinds.
#pragma once

#include <sstream>
#include <string>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit::deformation_checks {

inline std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

inline std::string fmt(const Vec3& v) { return "(" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + ")"; }

inline int checked_threads(int threads, const char* field) {
  if (threads < 0) {
    throw Error(ErrorCode::InvalidArgument, field, "thread count must be >= 0, got " + std::to_string(threads));
  }
  return resolve_threads(threads);
}

inline bool valid_blend(Blend b) { return b == Blend::Smooth || b == Blend::Quadratic || b == Blend::Linear; }

}  // namespace surfeledit::deformation_checks
