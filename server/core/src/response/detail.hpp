// Helpers shared by the collision-response files (private to the core).
#pragma once

#include <cmath>
#include <sstream>
#include <string>

#include "surfeledit/core/types.hpp"

namespace surfeledit::response_detail {

// Throws InvalidArgument naming `field` unless `v` is finite and >= `min` (> `min` when `strict`).
inline void require_at_least(double v, double min, const char* field, bool strict = false) {
  if (std::isfinite(v) && (strict ? v > min : v >= min)) return;
  std::ostringstream msg;
  msg << "must be finite and " << (strict ? "> " : ">= ") << min << ", got " << v;
  throw Error(ErrorCode::InvalidArgument, field, msg.str());
}

// Axis-aligned box of some rows of a #P by 3 array, grown by `margin` on every side.
struct Box {
  Vec3 lo = Vec3::Constant(INFINITY);
  Vec3 hi = Vec3::Constant(-INFINITY);
  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void grow(double margin) {
    lo.array() -= margin;
    hi.array() += margin;
  }
  bool contains(const Vec3& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
};

}  // namespace surfeledit::response_detail
