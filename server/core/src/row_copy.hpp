// Copies of chosen rows of #P by 3 arrays (row-major: row r is the 3 doubles at data() + 3 r), the
// session's per-step bulk moves: a step's before-image (session_history.cpp) and its `previous`
// positions (edit_session.cpp). Memory-bound, so at 1M surfels they run on the step's threads, each
// over fixed ranges of rows: the bytes written are the same whatever the split.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit::detail {

// One copy: row rows[k] of `from` to row k of `to` (gather), or to row rows[k] of `to` (`same_rows`).
struct RowCopy {
  const double* from = nullptr;  // #P by 3
  const IndexList* rows = nullptr;
  double* to = nullptr;          // #rows by 3, or #P by 3 with same_rows
  bool same_rows = false;
};

// Rows per task, and the fewest rows (all copies together) worth a second thread: about 0.3 ms of
// one-thread copying (waking a descheduled worker on a busy machine costs a scheduler tick, RESULTS §36).
constexpr std::size_t kRowCopyChunk = 8192;
constexpr std::size_t kRowCopyParallelMin = 100000;

inline void run_row_copies(const std::vector<RowCopy>& copies, int threads) {
  struct Task {
    const RowCopy* copy;
    std::size_t begin, end;
  };
  std::vector<Task> tasks;
  std::size_t total = 0;
  for (const RowCopy& c : copies) {
    const std::size_t n = c.rows->size();
    total += n;
    for (std::size_t b = 0; b < n; b += kRowCopyChunk) tasks.push_back({&c, b, std::min(n, b + kRowCopyChunk)});
  }
  auto run = [&](const Task& t) {
    const Index* rows = t.copy->rows->data();
    const double* from = t.copy->from;
    double* to = t.copy->to;
    if (t.copy->same_rows) {
      for (std::size_t k = t.begin; k < t.end; ++k) std::memcpy(to + 3 * rows[k], from + 3 * rows[k], 3 * sizeof(double));
    } else {
      for (std::size_t k = t.begin; k < t.end; ++k) std::memcpy(to + 3 * k, from + 3 * rows[k], 3 * sizeof(double));
    }
  };
  const std::ptrdiff_t n_tasks = static_cast<std::ptrdiff_t>(tasks.size());
  if (threads <= 1 || total < kRowCopyParallelMin) {
    for (const Task& t : tasks) run(t);
    return;
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::ptrdiff_t i = 0; i < n_tasks; ++i) run(tasks[static_cast<std::size_t>(i)]);
}

}  // namespace surfeledit::detail
