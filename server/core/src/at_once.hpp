// Two independent parts of one job run at once on two threads (internal header): Robust's reset beside its seed
// (collision/kernel_rows.hpp), the zero set's tree beside the boundary marks' whole-model tree (collision_simple.cpp),
// the hierarchical detector's narrow phase beside its trees (bvh/hierarchical_detector.cpp), the deformation fields'
// two trees (deformation.cpp).
#pragma once

#include <cstddef>
#include <exception>

#include "surfeledit/core/types.hpp"

namespace surfeledit::detail {

// Points below which a tree's build is not worth a second thread (~1.5 ms of one thread's build): a small model's
// reset would wait longer on a descheduled worker than it saves.
inline constexpr Index kAtOnceMinPoints = 16384;

// Whether a job over `points` points with `threads` threads runs its two parts at once (at_once's `parallel`).
inline bool at_once_pays(int threads, std::size_t points) {
  return threads > 1 && points >= static_cast<std::size_t>(kAtOnceMinPoints);
}

// Runs first() and second(), which share nothing they write: at once on two threads (OpenMP sections) when
// `parallel`, else one after the other. Each part runs on one thread (a parallel region inside one runs serially).
// An exception of either is rethrown once both ended, first()'s before second()'s, as one after the other throws it.
template <class First, class Second>
void at_once(bool parallel, First&& first, Second&& second) {
  if (!parallel) {
    first();
    second();
    return;
  }
  std::exception_ptr failed[2];
#pragma omp parallel sections num_threads(2)
  {
#pragma omp section
    try {
      first();
    } catch (...) {
      failed[0] = std::current_exception();
    }
#pragma omp section
    try {
      second();
    } catch (...) {
      failed[1] = std::current_exception();
    }
  }
  for (const std::exception_ptr& f : failed)
    if (f) std::rethrow_exception(f);
}

}  // namespace surfeledit::detail
