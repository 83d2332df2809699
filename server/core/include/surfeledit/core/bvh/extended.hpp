// Extended ("concave") narrow phase (docs/algorithms.md §5 "Extended", thesis §8.4): the hierarchy stays
// over the zero region, but a candidate deformable surfel is classified inside/outside against the
// ORIGINAL (undeformed) whole model, as the Robust algorithm does (docs/algorithms.md §4.4): its collision
// state flips when its inside state differs from the one before this step and its nearest original surfel is
// a zero surfel. The state before the step is cached with its step number; it is recomputed (at the surfel's
// previous position) only when the cache is not from the previous step.
//
// Use as the `narrow` policy of collide(): call begin_step() once per step, then collide().
// inside  <=>  (p - p2) . n2 < W  (strict, as in collision.hpp).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "surfeledit/core/inside_outside.hpp"

namespace surfeledit::bvh {

class ExtendedNarrow {
 public:
  // `original`: inside/outside over the original whole model (rows = model rows at reset);
  // `is_zero`: one flag per original row, 1 for zero surfels; `rows`: current model row count;
  // `threshold`: W, model units.
  ExtendedNarrow(std::shared_ptr<const InsideOutside> original, std::vector<std::uint8_t> is_zero, Index rows,
                 double threshold = 0.0);

  // Starts step `step` (strictly increasing): `current` and `previous` positions (#P by 3) must
  // stay alive until the step's collide() has returned.
  void begin_step(std::int64_t step, const Points& current, const Points& previous);
  // Narrow test of one candidate deformable row (called at most once per row per step).
  void operator()(Index row);

  // Collision state per model row (1 = colliding).
  const std::vector<std::uint8_t>& colliding() const { return colliding_; }
  IndexList colliding_rows() const;
  // Inside/outside evaluations made so far (two per candidate without the cache, one with it).
  std::int64_t evaluations() const { return evaluations_; }

  // Row bookkeeping, as CollisionDetector::on_removed / on_inserted (children copy their parent's state).
  void on_removed(const std::vector<bool>& keep);
  void on_inserted(const IndexList& parents);

 private:
  struct Cached {
    std::int64_t step = -1;  // step whose end state `inside` is
    std::uint8_t inside = 0;
  };
  bool classify(const Vec3& p, bool* nearest_is_zero) const;

  std::shared_ptr<const InsideOutside> original_;
  std::vector<std::uint8_t> is_zero_;   // by original row
  double threshold_;
  std::vector<Cached> cache_;           // by model row
  std::vector<std::uint8_t> colliding_; // by model row
  std::int64_t step_ = 0;
  const Points* current_ = nullptr;
  const Points* previous_ = nullptr;
  std::int64_t evaluations_ = 0;
};

}  // namespace surfeledit::bvh
