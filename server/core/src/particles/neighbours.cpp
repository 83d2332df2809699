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
  const Index n = static_cast<Index>(points.rows());
  if (n == 0) return Neighbourhood{{0}, {}};
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
  const auto cell_of = [&](Index i, int axis) {
    return std::min<std::int64_t>(static_cast<std::int64_t>((points(i, axis) - lo[axis]) / cell), dims_d[axis] - 1);
  };
  // Counting sort of the particles by cell.
  std::vector<std::int64_t> start(static_cast<std::size_t>(nx * ny * nz) + 1, 0), cell_id(n);
  for (Index i = 0; i < n; ++i) {
    cell_id[i] = cell_of(i, 0) + nx * (cell_of(i, 1) + ny * cell_of(i, 2));
    ++start[cell_id[i] + 1];
  }
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  IndexList sorted(n);
  {
    std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
    for (Index i = 0; i < n; ++i) sorted[fill[cell_id[i]]++] = i;
  }
  const double r2 = radius * radius;
  std::vector<IndexList> lists(n);
#pragma omp parallel for schedule(static) num_threads(resolve_threads(threads))
  for (Index i = 0; i < n; ++i) {
    const std::int64_t cx = cell_of(i, 0), cy = cell_of(i, 1), cz = cell_of(i, 2);
    IndexList& l = lists[i];
    for (std::int64_t z = std::max<std::int64_t>(cz - 1, 0); z <= std::min(cz + 1, nz - 1); ++z)
      for (std::int64_t y = std::max<std::int64_t>(cy - 1, 0); y <= std::min(cy + 1, ny - 1); ++y)
        for (std::int64_t x = std::max<std::int64_t>(cx - 1, 0); x <= std::min(cx + 1, nx - 1); ++x) {
          const std::int64_t c = x + nx * (y + ny * z);
          for (std::int64_t k = start[c]; k < start[c + 1]; ++k) {
            const Index j = sorted[k];
            if (j != i && (points.row(j) - points.row(i)).squaredNorm() <= r2) l.push_back(j);
          }
        }
    std::sort(l.begin(), l.end());
  }
  return to_csr(lists);
}

}  // namespace surfeledit
