// Improved Simple Algo (§4.2 of docs/algorithms.md): the Simple kernel swept in ascending row order
// with spatial coherence. After testing a point s1 with |d| > sqrt(H), every not-yet-settled
// deformable surfel strictly inside B(p1, |d|) (which holds no zero surfel) takes s1's state without
// a query, with depth |d| - e (e: its distance to p1, a lower bound of its own |d|). H is the mean
// |d|^2 of the points tested in the previous step; H = 0 on the first step after a reset (propagate
// from every test). The result depends on the order, so the sweep is single-threaded, and it cannot
// run on candidates only (it settles surfels from the queries of surfels a broad phase skips).
#pragma once

#include "row_detector.hpp"
#include "simple_kernel.hpp"

namespace surfeledit::detail {

class ImprovedSweep {
 public:
  ImprovedSweep() = default;
  explicit ImprovedSweep(const CollisionParams&) {}  // one thread always: nothing to take from the settings
  void reset() { mean_dist2_ = 0.0; }

  Tally run(const SimpleKernel& kernel, const IndexList& rows, RowStates<SimpleKernel::State>& states,
            const CollisionScene& scene, const Points& previous, const std::vector<std::uint8_t>* candidate,
            int threads, std::vector<std::uint8_t>& hit);

 private:
  double mean_dist2_ = 0.0;  // H: mean |d|^2 of the previous step's tested points
};

}  // namespace surfeledit::detail
