// Boolean operations of two closed surfel models (thesis §12.4.1, docs/particles.md "Booleans"): every
// surfel of each model is classified against the other model with the inside/outside operator
// (docs/algorithms.md §2), kept or dropped by the operation, and the kept surfels near the other surface
// are the feature surfels the blend tool starts from.
//   union:        A outside B, B outside A
//   intersection: A inside B,  B inside A
//   difference:   A outside B, B inside A with its normals flipped (A - B)
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

enum class BooleanOp : std::uint8_t { Union = 0, Intersection = 1, Difference = 2 };
constexpr EnumNames<BooleanOp, 3> names_of(BooleanOp) {
  return {{{BooleanOp::Union, "union"}, {BooleanOp::Intersection, "intersection"},
           {BooleanOp::Difference, "difference"}}};
}

struct BooleanParams {
  double feature_factor = 1.0;  // a kept surfel is a feature surfel when the other model's nearest surfel is
                                // within this x (its radius + that surfel's radius) and its offset to that
                                // surfel's plane within this x its radius (thesis: about one radius), >= 0
  int threads = 0;              // worker threads (0 = all); the result does not depend on it
};

// Throws InvalidArgument naming the field.
void validate(const BooleanParams& params);

struct BooleanClassification {
  std::vector<bool> keep_a;  // #A: A's surfel stays
  std::vector<bool> keep_b;  // #B
  IndexList features_a;      // kept rows of A near B's surface, ascending
  IndexList features_b;      // kept rows of B near A's surface, ascending
};

// `pa`, `na`, `ra`: model A (#A by 3 positions, unit outward normals, #A radii); likewise B. Both closed.
BooleanClassification classify_boolean(const Points& pa, const Points& na, const Values& ra, const Points& pb,
                                       const Points& nb, const Values& rb, BooleanOp op,
                                       const BooleanParams& params = {});

}  // namespace surfeledit
