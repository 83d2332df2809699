// Small helpers every part of the core uses: timing, worker-thread counts and row compaction.
#pragma once

#include <chrono>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

// Milliseconds elapsed since `start` (steady clock).
inline double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// Worker threads for a `threads` setting: the value itself when > 0, else all OpenMP threads.
int resolve_threads(int threads);

// The hardware threads (std::thread::hardware_concurrency, at least 1): the `threads` setting's upper bound.
int hardware_threads();

// Keeps the entries (rows) whose flag in `keep` is set, in order; `keep` has one flag per entry.
template <typename T>
void compact(std::vector<T>& v, const std::vector<bool>& keep) {
  std::size_t j = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (keep[i]) v[j++] = v[i];
  v.resize(j);
}
void compact(Points& a, const std::vector<bool>& keep);  // #P by 3 -> #kept by 3
void compact(Values& a, const std::vector<bool>& keep);  // #P -> #kept

// Old row -> new row after a removal (`keep`: one flag per old row), -1 for removed rows.
IndexList remap_rows(const std::vector<bool>& keep);

}  // namespace surfeledit
