// The Verlet list: rebuild test and the exact filter (the same distance expression as neighbours_grid).
#include "surfeledit/core/particles/verlet.hpp"

#include <algorithm>

namespace surfeledit {

namespace {

// True when `list.wide` still holds every pair within `radius` of `points`.
bool still_valid(const Points& points, double radius, double skin, const VerletList& list) {
  if (skin <= 0.0 || list.anchor.rows() != points.rows() || list.radius != radius || list.skin != skin) return false;
  // Each of two particles moved less than `limit`, so their distance grew by less than 2 limit < skin.
  // The margin (1e-6 skin) covers the rounding of the distances compared here and in the builder.
  const double limit = 0.5 * skin * (1.0 - 1e-6), limit2 = limit * limit;
  const Index n = static_cast<Index>(points.rows());
  const double* x = points.data();
  const double* a = list.anchor.data();
  double worst = 0.0;
  for (Index k = 0; k < 3 * n; k += 3) {
    const double dx = x[k] - a[k], dy = x[k + 1] - a[k + 1], dz = x[k + 2] - a[k + 2];
    worst = std::max(worst, dx * dx + dy * dy + dz * dz);
  }
  return worst < limit2;
}

}  // namespace

void neighbours_verlet(const Points& points, double radius, double skin, int threads, VerletList& list,
                       Neighbourhood& out) {
  if (!still_valid(points, radius, skin, list)) {
    if (skin <= 0.0) {  // no skin: the list would be rebuilt every call, so it is the grid query itself
      neighbours_grid(points, radius, threads, list.grid, out);
      list.anchor.resize(0, 3);
      ++list.rebuilds;
      return;
    }
    neighbours_grid(points, radius + skin, threads, list.grid, list.wide);
    list.anchor = points;
    list.radius = radius;
    list.skin = skin;
    ++list.rebuilds;
  }
  // Filter, rows ascending and each row in the wide list's ascending order: the grid builder's lists.
  const Index n = static_cast<Index>(points.rows());
  const double r2 = radius * radius;
  const double* x = points.data();
  const std::int64_t* wo = list.wide.offsets.data();
  const Index* wi = list.wide.indices.data();
  out.offsets.resize(static_cast<std::size_t>(n) + 1);
  out.indices.resize(list.wide.indices.size());  // an upper bound; shrunk below
  Index* dst = out.indices.data();
  std::int64_t used = 0;
  out.offsets[0] = 0;
  for (Index i = 0; i < n; ++i) {
    const double xi = x[3 * i], yi = x[3 * i + 1], zi = x[3 * i + 2];
    for (std::int64_t c = wo[i]; c < wo[i + 1]; ++c) {
      const Index j = wi[c];
      const double dx = x[3 * j] - xi, dy = x[3 * j + 1] - yi, dz = x[3 * j + 2] - zi;
      dst[used] = j;
      used += static_cast<std::int64_t>(dx * dx + dy * dy + dz * dz <= r2);
    }
    out.offsets[i + 1] = used;
  }
  out.indices.resize(static_cast<std::size_t>(used));
}

}  // namespace surfeledit
