// Copies of chosen rows of #P by 3 arrays (row-major: row r is the 3 doubles at data() + 3 r), the
// session's per-step bulk moves: a step's before-image (session_history.cpp) and its `previous`
// positions (edit_session.cpp). One thread: split over the step's two threads they were slower on the
// shared machine (a descheduled worker stalls each region, RESULTS §46), as the detector's and the
// deformation's small loops were (§36).
#pragma once

#include <cstddef>
#include <cstring>
#include <vector>

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

inline void run_row_copies(const std::vector<RowCopy>& copies) {
  for (const RowCopy& c : copies) {
    const Index* rows = c.rows->data();
    const std::size_t n = c.rows->size();
    if (c.also) {
      double* const to2 = c.also;
      for (std::size_t k = 0; k < n; ++k) {
        const double* r = c.from + 3 * rows[k];
        double* t = c.same_rows ? c.to + 3 * rows[k] : c.to + 3 * k;
        std::memcpy(t, r, 3 * sizeof(double));
        std::memcpy(to2 + 3 * rows[k], r, 3 * sizeof(double));
      }
    } else if (c.same_rows) {
      for (std::size_t k = 0; k < n; ++k) std::memcpy(c.to + 3 * rows[k], c.from + 3 * rows[k], 3 * sizeof(double));
    } else {
      for (std::size_t k = 0; k < n; ++k) std::memcpy(c.to + 3 * k, c.from + 3 * rows[k], 3 * sizeof(double));
    }
  }
}

}  // namespace surfeledit::detail
