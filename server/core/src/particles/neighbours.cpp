// Range neighbourhoods by k-d tree or uniform grid, both sorted by index and without the particle itself.
#include "surfeledit/core/particles/neighbours.hpp"

#include <algorithm>
#include <cmath>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// CSR from per-particle lists (each already sorted, self excluded).
Neighbourhood to_csr(std::vector<IndexList>& lists) {
  Neighbourhood nb;
  nb.offsets.assign(lists.size() + 1, 0);
  for (std::size_t i = 0; i < lists.size(); ++i) nb.offsets[i + 1] = nb.offsets[i] + static_cast<std::int64_t>(lists[i].size());
  nb.indices.reserve(static_cast<std::size_t>(nb.offsets.back()));
  for (auto& l : lists) nb.indices.insert(nb.indices.end(), l.begin(), l.end());
  return nb;
}

}  // namespace

Neighbourhood neighbours_kdtree(const Points& points, double radius, int threads) {
  const Index n = static_cast<Index>(points.rows());
  if (n == 0) return Neighbourhood{{0}, {}};
  KdTreeParams kp;
  kp.threads = threads;
  const KdTree tree(points, kp);
  const RadiusResult hits = tree.radius(points, radius);
  std::vector<IndexList> lists(n);
#pragma omp parallel for schedule(static) num_threads(resolve_threads(threads))
  for (Index i = 0; i < n; ++i) {
    IndexList& l = lists[i];
    for (std::int64_t k = hits.offsets[i]; k < hits.offsets[i + 1]; ++k)
      if (hits.indices[k] != i) l.push_back(hits.indices[k]);
    std::sort(l.begin(), l.end());
  }
  return to_csr(lists);
}

Neighbourhood neighbours_grid(const Points& points, double radius, int threads) {
  GridWorkspace ws;
  Neighbourhood nb;
  neighbours_grid(points, radius, threads, ws, nb);
  return nb;
}

void neighbours_grid(const Points& points, double radius, int threads, GridWorkspace& ws, Neighbourhood& nb) {
  const Index n = static_cast<Index>(points.rows());
  if (n == 0) {
    nb.offsets.assign(1, 0);
    nb.indices.clear();
    return;
  }
  const Vec3 lo = points.colwise().minCoeff().transpose();
  const Vec3 extent = points.colwise().maxCoeff().transpose() - lo;
  // Cells of at least `radius`, and no more than ~8 cells per particle.
  double cell = radius;
  const auto cells_for = [&](double c) {
    return ((extent / c).array().floor() + 1.0).matrix().eval();
  };
  while (cells_for(cell).prod() > 8.0 * n + 27.0) cell *= 2.0;
  const Eigen::Vector3d dims_d = cells_for(cell);
  const std::int64_t nx = static_cast<std::int64_t>(dims_d[0]), ny = static_cast<std::int64_t>(dims_d[1]),
                     nz = static_cast<std::int64_t>(dims_d[2]);
  // The cell of every particle and a counting sort of the particles by cell, with their coordinates copied
  // in that order so that the candidates of a row of cells are contiguous in memory.
  ws.cell.resize(static_cast<std::size_t>(n));
  ws.start.assign(static_cast<std::size_t>(nx * ny * nz) + 1, 0);
  const auto coord = [&](Index i, int axis) {
    return std::min<std::int64_t>(static_cast<std::int64_t>((points(i, axis) - lo[axis]) / cell),
                                  static_cast<std::int64_t>(dims_d[axis]) - 1);
  };
  for (Index i = 0; i < n; ++i) {
    ws.cell[i] = coord(i, 0) + nx * (coord(i, 1) + ny * coord(i, 2));
    ++ws.start[ws.cell[i] + 1];
  }
  for (std::size_t c = 1; c < ws.start.size(); ++c) ws.start[c] += ws.start[c - 1];
  ws.sorted.resize(static_cast<std::size_t>(n));
  ws.sp.resize(3 * static_cast<std::size_t>(n));
  ws.fill.assign(ws.start.begin(), ws.start.end() - 1);
  for (Index i = 0; i < n; ++i) {
    const std::int64_t k = ws.fill[ws.cell[i]]++;
    ws.sorted[k] = i;
    for (int axis = 0; axis < 3; ++axis) ws.sp[3 * k + axis] = points(i, axis);
  }
  // Pass 1: each particle's neighbours in cell order, by blocks of rows (concatenated in row order). The
  // candidate loop is branchless: every candidate is written, the count advances only for a neighbour.
  const double r2 = radius * radius;
  constexpr Index kBlock = 1024;
  const Index blocks = (n + kBlock - 1) / kBlock;
  ws.found.resize(static_cast<std::size_t>(blocks));
  std::vector<std::int64_t>& offsets = nb.offsets;
  offsets.assign(static_cast<std::size_t>(n) + 1, 0);
  const std::int64_t* start = ws.start.data();
  const double* sp = ws.sp.data();
  const Index* sorted = ws.sorted.data();
#pragma omp parallel for schedule(dynamic) num_threads(resolve_threads(threads))
  for (Index blk = 0; blk < blocks; ++blk) {
    IndexList& out = ws.found[blk];
    std::size_t used = 0;
    for (Index i = blk * kBlock; i < std::min(n, (blk + 1) * kBlock); ++i) {
      const std::size_t before = used;
      const std::int64_t c = ws.cell[i], cx = c % nx, cy = (c / nx) % ny, cz = c / (nx * ny);
      const double xi = points(i, 0), yi = points(i, 1), zi = points(i, 2);
      const std::int64_t x0 = std::max<std::int64_t>(cx - 1, 0), x1 = std::min(cx + 1, nx - 1);
      for (std::int64_t z = std::max<std::int64_t>(cz - 1, 0); z <= std::min(cz + 1, nz - 1); ++z)
        for (std::int64_t y = std::max<std::int64_t>(cy - 1, 0); y <= std::min(cy + 1, ny - 1); ++y) {
          const std::int64_t row = nx * (y + ny * z);  // cells x0..x1 of this row are contiguous
          const std::int64_t k0 = start[row + x0], k1 = start[row + x1 + 1];
          if (out.size() < used + static_cast<std::size_t>(k1 - k0)) out.resize(2 * (used + (k1 - k0)) + 64);
          Index* dst = out.data();
          for (std::int64_t k = k0; k < k1; ++k) {
            const double dx = sp[3 * k] - xi, dy = sp[3 * k + 1] - yi, dz = sp[3 * k + 2] - zi;
            const Index j = sorted[k];
            dst[used] = j;
            used += static_cast<std::size_t>((dx * dx + dy * dy + dz * dz <= r2) & (j != i));
          }
        }
      offsets[i + 1] = static_cast<std::int64_t>(used - before);
    }  // `out` keeps its size (>= used) as capacity for the next call
  }
  for (Index i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  // Pass 2: the relation is symmetric, so its transpose is itself; building the transpose by visiting the
  // rows in ascending order lists every row ascending, without a sort.
  nb.indices.resize(static_cast<std::size_t>(offsets.back()));
  ws.cursor.assign(offsets.begin(), offsets.end() - 1);
  Index* indices = nb.indices.data();
  std::int64_t* cursor = ws.cursor.data();
  for (Index blk = 0; blk < blocks; ++blk) {
    const Index* f = ws.found[blk].data();
    std::size_t k = 0;
    for (Index i = blk * kBlock; i < std::min(n, (blk + 1) * kBlock); ++i)
      for (std::int64_t e = offsets[i]; e < offsets[i + 1]; ++e) indices[cursor[f[k++]]++] = i;
  }
}

}  // namespace surfeledit
