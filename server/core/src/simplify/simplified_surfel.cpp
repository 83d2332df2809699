#include "surfeledit/core/simplify/simplified_surfel.hpp"

#include <algorithm>
#include <omp.h>

#include "surfeledit/core/simplify/surface_variation.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

SimplifiedSurfel simplify_cluster(const Points& positions, const Points& normals, const Values& radii,
                                  const Index* rows, std::size_t n) {
  SimplifiedSurfel s;
  s.count = static_cast<Index>(n);
  if (n == 0) return s;
  Vec3 sum = Vec3::Zero(), nsum = Vec3::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    sum += positions.row(rows[k]).transpose();
    nsum += normals.row(rows[k]).transpose();
  }
  s.position = sum / static_cast<double>(n);
  const double len = nsum.norm();
  if (len > 1e-12 * static_cast<double>(n)) {
    s.normal = nsum / len;
  } else {
    Vec3 axis = covariance_of(positions, rows, n).eigenvectors.col(0);
    if (axis.dot(normals.row(rows[0]).transpose()) < 0.0) axis = -axis;
    s.normal = axis.normalized();
  }
  double radius = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double r = radii.size() ? radii[rows[k]] : 0.0;
    radius = std::max(radius, (positions.row(rows[k]).transpose() - s.position).norm() + r);
  }
  s.radius = radius;
  return s;
}

std::vector<SimplifiedSurfel> simplify(const Points& positions, const Points& normals, const Values& radii,
                                       const Clustering& clusters, int threads) {
  const Index n = clusters.size();
  std::vector<SimplifiedSurfel> out(static_cast<std::size_t>(n));
  const int t = resolve_threads(threads);
#pragma omp parallel for schedule(dynamic, 256) num_threads(t)
  for (Index c = 0; c < n; ++c) {
    out[c] = simplify_cluster(positions, normals, radii, clusters.rows(c), static_cast<std::size_t>(clusters.count(c)));
  }
  return out;
}

}  // namespace surfeledit
