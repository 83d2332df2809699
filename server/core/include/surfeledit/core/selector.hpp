// Geometric selectors for choosing surfels by their current position.
#pragma once

#include "surfeledit/core/types.hpp"

namespace surfeledit {

struct Selector {
  enum class Kind : std::uint8_t { Sphere = 0, Box = 1 };
  Kind kind = Kind::Sphere;
  Vec3 center = Vec3::Zero();        // sphere centre or box centre, model units
  double radius = 0.0;               // sphere radius (real distance, not squared)
  Vec3 half_extents = Vec3::Zero();  // axis-aligned box half extents
};

// Throws InvalidArgument naming `field` on non-finite or negative dimensions.
void validate(const Selector& selector, const std::string& field);
// Rows whose position lies inside the selector (boundary included), ascending.
IndexList select_rows(const Points& positions, const Selector& selector);

}  // namespace surfeledit
