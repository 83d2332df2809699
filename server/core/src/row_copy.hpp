// Copies of chosen rows of #P by 3 arrays (row-major: row r is the 3 doubles at data() + 3 r), the
// session's per-step bulk moves: a step's before-image (session_history.cpp) and its `previous`
// positions (session_step.cpp). Large copies are split over the step's threads: at 1M surfels a drag step
// copies ~7 MB of positions into its before-image and again into `previous`, milliseconds of one thread's
// copying and page faults (RESULTS §70; at load 6-7 on two cores the split was slower, §46.3, at load 2 it
// is not).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

#include "share_chunks.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::detail {

// One copy: row rows[k] of `from` to row k of `to` (gather), or to row rows[k] of `to` (`same_rows`);
// with `also`, the same pass writes it to row rows[k] of `also` too (one read of `from` for two copies).
struct RowCopy {
  const double* from = nullptr;  // #P by 3
  const IndexList* rows = nullptr;
  double* to = nullptr;          // #rows by 3, or #P by 3 with same_rows
  bool same_rows = false;
  double* also = nullptr;        // null, or #P by 3: a second destination, row rows[k]
};

// Rows [k0, k1) of one copy.
inline void copy_range(const RowCopy& c, std::size_t k0, std::size_t k1) {
  const Index* rows = c.rows->data();
  if (c.also) {
    double* const to2 = c.also;
    for (std::size_t k = k0; k < k1; ++k) {
      const double* r = c.from + 3 * rows[k];
      double* t = c.same_rows ? c.to + 3 * rows[k] : c.to + 3 * k;
      std::memcpy(t, r, 3 * sizeof(double));
      std::memcpy(to2 + 3 * rows[k], r, 3 * sizeof(double));
    }
  } else if (c.same_rows) {
    for (std::size_t k = k0; k < k1; ++k) std::memcpy(c.to + 3 * rows[k], c.from + 3 * rows[k], 3 * sizeof(double));
  } else {
    for (std::size_t k = k0; k < k1; ++k) std::memcpy(c.to + 3 * k, c.from + 3 * rows[k], 3 * sizeof(double));
  }
}

// Rows copied (summed over the copies) from which `threads` > 1 split them: about a millisecond of one
// thread's work, as for the deformation's loop (deformation_step.cpp).
constexpr std::size_t kParallelMinRowCopies = 200000;

// Runs the copies; with `threads` > 1 and enough rows, each copy's rows are split in parts of consecutive rows
// that the threads share (every row is written by exactly one thread: the same bytes either way).
inline void run_row_copies(const std::vector<RowCopy>& copies, int threads = 1) {
  std::size_t total = 0;
  for (const RowCopy& c : copies) total += c.rows->size();
  if (threads <= 1 || total < kParallelMinRowCopies) {
    for (const RowCopy& c : copies) copy_range(c, 0, c.rows->size());
    return;
  }
  // Parts of kRowsPerPart rows of each copy in turn (~0.1 ms each), shared without waiting for a descheduled helper.
  constexpr std::size_t kRowsPerPart = 16384;
  std::vector<std::size_t> first_part;  // copies[i]'s parts start at first_part[i]
  std::size_t parts = 0;
  for (const RowCopy& c : copies) {
    first_part.push_back(parts);
    parts += (c.rows->size() + kRowsPerPart - 1) / kRowsPerPart;
  }
  share_chunks(threads, static_cast<Index>(parts), [&](Index part) {
    const std::size_t p = static_cast<std::size_t>(part);
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(first_part.begin(), first_part.end(), p) -
                                                   first_part.begin()) - 1;
    const std::size_t k0 = (p - first_part[i]) * kRowsPerPart;
    copy_range(copies[i], k0, std::min(copies[i].rows->size(), k0 + kRowsPerPart));
  });
}

}  // namespace surfeledit::detail
