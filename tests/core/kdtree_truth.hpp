// Brute-force truth for the k-d tree tests: seeded clouds, sorted squared distances, and the checks of a kNN or
// radius answer against them.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "random_data.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit::test {

// #n by 3 points uniform in offset + scale * [-1, 1]^3.
inline Points random_cloud(int n, std::uint64_t seed, double scale = 1.0, const Vec3& offset = Vec3::Zero()) {
  return uniform_cloud(n, seed, scale, offset);
}

// Squared distances (model units^2) from q to every row of `points` listed in `rows` (all rows when empty).
inline std::vector<double> brute_dist2(const Points& points, const Vec3& q, const IndexList& rows = {}) {
  std::vector<double> d;
  if (rows.empty()) {
    for (Eigen::Index i = 0; i < points.rows(); ++i) d.push_back((points.row(i).transpose() - q).squaredNorm());
  } else {
    for (Index i : rows) d.push_back((points.row(i).transpose() - q).squaredNorm());
  }
  std::sort(d.begin(), d.end());
  return d;
}

// Checks a kNN answer: ascending, the distances equal the k smallest brute-force ones (as a multiset,
// so ties may pick any index), and every returned dist2 is the true distance of the returned row.
inline void expect_knn_matches(const Points& points, const Vec3& q, int k, const IndexList& idx,
                        const std::vector<double>& d2, const IndexList& rows = {}) {
  const std::vector<double> truth = brute_dist2(points, q, rows);
  const std::size_t expect = std::min<std::size_t>(static_cast<std::size_t>(k), truth.size());
  ASSERT_EQ(idx.size(), expect);
  ASSERT_EQ(d2.size(), expect);
  for (std::size_t j = 0; j < expect; ++j) {
    const double tol = 1e-12 * (1.0 + truth[j]);
    EXPECT_NEAR(d2[j], truth[j], tol) << "rank " << j;
    ASSERT_GE(idx[j], 0);
    ASSERT_LT(idx[j], points.rows());
    EXPECT_NEAR((points.row(idx[j]).transpose() - q).squaredNorm(), d2[j], tol);
    if (j > 0) {
      EXPECT_LE(d2[j - 1], d2[j]);
    }
    if (!rows.empty()) {
      EXPECT_NE(std::find(rows.begin(), rows.end(), idx[j]), rows.end());
    }
  }
  // no duplicate rows
  IndexList sorted = idx;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end());
}

inline void expect_radius_matches(const Points& points, const Vec3& q, double r, const IndexList& idx,
                           const std::vector<double>& d2, const IndexList& rows = {}) {
  std::vector<double> truth;
  for (double d : brute_dist2(points, q, rows)) {
    if (d <= r * r) truth.push_back(d);
  }
  ASSERT_EQ(idx.size(), truth.size()) << "radius " << r;
  for (std::size_t j = 0; j < truth.size(); ++j) {
    EXPECT_NEAR(d2[j], truth[j], 1e-12 * (1.0 + truth[j]));
    EXPECT_NEAR((points.row(idx[j]).transpose() - q).squaredNorm(), d2[j], 1e-12 * (1.0 + truth[j]));
    if (j > 0) {
      EXPECT_LE(d2[j - 1], d2[j]);
    }
  }
}

// The shape of the detectors' exact nearest trees (leaves of 128, cells for nearest_from), one thread, with or without
// oriented node boxes (`frames`) and a turned frame (`align`), scanned by `scan`.
inline KdTreeParams nearest_params(KdScan scan, bool frames, bool align) {
  KdTreeParams p;
  p.leaf_size = 128;
  p.threads = 1;
  p.cells = true;
  p.frames = frames;
  p.align = align;
  p.scan = scan;
  return p;
}

// A side x side lattice of spacing h on the plane z = 0 (or, `bent`, on a cylinder of radius side * h / 2 about
// the x axis), jittered by 1e-3 h (seeded), turned by a rotation no face of the axes' boxes survives, scaled and
// moved to `offset`; `turn`: another rotation (the identity: the plane along the axes).
inline Points turned_surface(
    int side, double h, bool bent, double scale, const Vec3& offset,
    const Mat3& turn = Eigen::AngleAxisd(0.7, Vec3(0.4, -0.3, 0.85).normalized()).toRotationMatrix()) {
  std::mt19937_64 rng(91);
  std::uniform_real_distribution<double> jitter(-1e-3 * h, 1e-3 * h);
  const double radius = 0.5 * side * h;
  Points p(side * side, 3);
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      const double u = (i - side / 2) * h + jitter(rng), v = (j - side / 2) * h + jitter(rng);
      Vec3 x(u, v, jitter(rng));
      if (bent) x = Vec3(u, radius * std::sin(v / radius), radius * (1.0 - std::cos(v / radius)));
      p.row(i * side + j) = (offset + scale * (turn * x)).transpose();
    }
  }
  return p;
}

// Queries at 0 to 40 spacings from the surface's middle region (either side), seeded.
inline Points queries_about(const Points& surface, int n, double h, double scale) {
  std::mt19937_64 rng(92);
  std::uniform_int_distribution<Eigen::Index> row(0, surface.rows() - 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0), far(0.0, 40.0);
  Points q(n, 3);
  for (int i = 0; i < n; ++i) {
    const Vec3 dir = Vec3(u(rng), u(rng), u(rng)).normalized();
    q.row(i) = surface.row(row(rng)) + (far(rng) * h * scale * dir).transpose();
  }
  return q;
}

}  // namespace surfeledit::test
