// The step's largest displacement of a hierarchical detector's deformable rows (hierarchical_detector.hpp):
// what the bounded deformable tree (bvh.hpp, step_bounded) grows its boxes by and surfel/tree adds to
// every ball's radius.
#pragma once

#include <vector>

#include "surfeledit/core/collision.hpp"

namespace surfeledit::detail {

struct StepShift {
  double shift = 0.0;  // reach plus the largest radius growth since the last step, model units
  double reach = 0.0;  // the largest own displacement |p - previous| of a deformable row, model units
};

// One pass over the `deformable` rows: the largest |position - previous| (reach) and that plus the
// largest radius growth against `prev_radius` (shift, by index into `deformable`); prev_radius takes the
// new radii. Squared lengths in the loop, one square root; both rounded upwards.
StepShift step_shift(const CollisionScene& scene, const Points& previous, const IndexList& deformable,
                     std::vector<double>& prev_radius);

}  // namespace surfeledit::detail
