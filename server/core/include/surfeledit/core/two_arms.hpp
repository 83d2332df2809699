// The two-arm scene of collaborative editing (issue 11 §1, docs/collaboration.md): a box body with two
// capsule arms standing on it, arm A at x = -0.4 and arm B at x = +0.4 (each slightly sunk into the body).
// Two tools move one arm each: tool "a" arm A (its zero region the body and arm B), tool "b" arm B.
// Shared by the tool tests and bench/core/bench_tools.cpp; the analytic solids are the exact truth.
#pragma once

#include <memory>

#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct TwoArms {
  static constexpr double kArmRadius = 0.1;   // capsule radius, model units
  static constexpr double kArmHalf = 0.25;    // capsule half length (segment), model units
  static constexpr double kArmX = 0.4;        // |x| of each arm's axis
  static constexpr double kArmZ = 0.2 + kArmHalf + kArmRadius - 0.03;  // z of the capsule centres
  static Vec3 body_half() { return Vec3(0.7, 0.2, 0.2); }  // the box's half extents, centred at the origin

  SampledSurfels surfels;  // #P rows: part 0 body, 1 arm A, 2 arm B
  IdList body, a, b;       // rows of each part, ascending (= surfel ids of model())

  // Samples the scene (`params`: spacing, seed, jitter).
  explicit TwoArms(const SampleParams& params);
  // The sampled surfels as a model (ids 0..#P-1 in row order).
  SurfelModel model() const;
  // The exact solids: the body, and the arms with their centre moved by `offset` (where a tool moved them).
  static std::unique_ptr<Solid> body_solid();
  static std::unique_ptr<Solid> arm_a_solid(const Vec3& offset = Vec3::Zero());
  static std::unique_ptr<Solid> arm_b_solid(const Vec3& offset = Vec3::Zero());
  // x ∪ y, ascending (region specs: zero = body ∪ the other arm).
  static IdList join(IdList x, const IdList& y);
};

}  // namespace surfeledit
