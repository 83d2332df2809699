// Surface variation of a point neighbourhood (Pauly, Gross, Kobbelt 2002; thesis §9.2):
// sigma = l0 / (l0 + l1 + l2), the eigenvalues of the neighbourhood's covariance matrix with l0 the
// smallest. 0 for points on a plane, 1/3 for isotropic scatter; an estimate of curvature.
#pragma once

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

// Centroid and principal axes of a set of points.
struct Covariance {
  Vec3 centroid = Vec3::Zero();     // mean position, model units
  Vec3 eigenvalues = Vec3::Zero();  // ascending: l0 <= l1 <= l2, squared model units (covariance / count)
  Mat3 eigenvectors = Mat3::Identity();  // column i belongs to eigenvalues[i] (unit)
  Index count = 0;                  // number of points

  // Surface variation l0 / (l0 + l1 + l2); 0 when all points coincide (or fewer than 2).
  double variation() const;
  // Unit axis of largest variance (eigenvector of l2).
  Vec3 largest_axis() const { return eigenvectors.col(2); }
};

// Covariance of the points rows[0 .. n) of `positions` (two-pass, centred: precise anywhere in space).
Covariance covariance_of(const Points& positions, const Index* rows, std::size_t n);
inline Covariance covariance_of(const Points& positions, const IndexList& rows) {
  return covariance_of(positions, rows.data(), rows.size());
}

// Surface variation of the neighbourhood rows[0 .. n).
inline double surface_variation(const Points& positions, const Index* rows, std::size_t n) {
  return covariance_of(positions, rows, n).variation();
}

// Per-point surface variation: for each row listed in `rows` (all rows when empty) the variation of its
// k nearest points in `tree` (itself included). Returns #rows(positions) values; rows not listed get 0.
// Multithreaded over points (`threads`, 0 = all).
Values surface_variation(const Points& positions, const KdTree& tree, int k, const IndexList& rows = {},
                         int threads = 0);

}  // namespace surfeledit
