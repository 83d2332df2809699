#include "surfeledit/core/util.hpp"

#include <omp.h>

#include <algorithm>
#include <thread>

namespace surfeledit {

int resolve_threads(int threads) { return threads > 0 ? threads : omp_get_max_threads(); }

int hardware_threads() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

void compact(Points& a, const std::vector<bool>& keep) {
  Eigen::Index j = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    if (keep[static_cast<std::size_t>(i)]) a.row(j++) = a.row(i);
  a.conservativeResize(j, 3);
}

void compact(Values& a, const std::vector<bool>& keep) {
  Eigen::Index j = 0;
  for (Eigen::Index i = 0; i < a.size(); ++i)
    if (keep[static_cast<std::size_t>(i)]) a[j++] = a[i];
  a.conservativeResize(j);
}

IndexList remap_rows(const std::vector<bool>& keep) {
  IndexList out(keep.size(), -1);
  Index j = 0;
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) out[i] = j++;
  return out;
}

}  // namespace surfeledit
