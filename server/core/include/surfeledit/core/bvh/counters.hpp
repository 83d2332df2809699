// Work counters of one query or one step, the terms of the cost model T = Nv Cv + Np Cp + Nu Cu
// (thesis Eq. 8.11). Benchmarks report them beside the time.
#pragma once

#include <cstdint>

namespace surfeledit::bvh {

struct BvhCounters {
  std::int64_t nv = 0;  // Nv: bounding-volume overlap tests (box/box and box/surfel)
  std::int64_t np = 0;  // Np: primitive (narrow-phase) tests handed to the narrow policy
  std::int64_t nu = 0;  // Nu: bounding-volume updates (boxes recomputed by a refit or an insertion)

  BvhCounters& operator+=(const BvhCounters& o) {
    nv += o.nv;
    np += o.np;
    nu += o.nu;
    return *this;
  }
};

}  // namespace surfeledit::bvh
