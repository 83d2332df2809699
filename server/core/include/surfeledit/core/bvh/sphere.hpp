// Bounding sphere (thesis ch. 9 uses sphere trees; here a box kind of the generic tree) and the
// sphere of one surfel (centre = position, radius = surfel radius) used by surfel/tree queries.
// Model units throughout.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "surfeledit/core/bvh/aabb.hpp"

namespace surfeledit::bvh {

struct Sphere {
  Vec3 center = Vec3::Zero();  // model units
  double radius = -1.0;        // model units; < 0 = empty

  bool empty() const { return radius < 0.0; }

  // Grows (radius only, centre kept) to contain the ball (p, r).
  void expand(const Vec3& p, double r) {
    if (empty()) {
      center = p;
      radius = r;
      return;
    }
    radius = std::max(radius, (p - center).norm() + r);
  }
  // Grows (radius only) to contain a child sphere.
  void enclose(const Sphere& child) { expand(child.center, child.radius); }
  // A parent's sphere after the build: contains its children (thesis §10.1.1).
  static constexpr bool kContainsChildren = true;
  void grow_over_child(const Sphere& child) { enclose(child); }
  void inflate(double m) { radius += m; }
  // Diameter at least `extent` (thesis §10.1.1).
  void enforce_min_extent(double extent) { radius = std::max(radius, 0.5 * extent); }
  bool contains(const Vec3& p, double r) const { return (p - center).norm() + r <= radius * (1.0 + 1e-12) + 1e-300; }
  bool contains(const Sphere& s) const { return contains(s.center, s.radius); }

  // Centroid of the positions, radius reaching the farthest ball.
  static Sphere fit(const Points& positions, const Values& radii, const Index* rows, std::size_t n) {
    Sphere s;
    Vec3 sum = Vec3::Zero();
    std::size_t live = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (rows[k] < 0) continue;
      sum += positions.row(rows[k]).transpose();
      ++live;
    }
    if (live == 0) return s;
    s.center = sum / double(live);
    s.radius = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const Index i = rows[k];
      if (i < 0) continue;
      s.radius = std::max(s.radius, (positions.row(i).transpose() - s.center).norm() + radius_of(radii, i));
    }
    // One ulp-scale margin so that the containment check of the same balls never fails by rounding.
    s.radius *= 1.0 + 1e-12;
    return s;
  }
  // Largest-variance coordinate axis, as for the AABB.
  static Vec3 split_direction(const Sphere&, const Points& positions, const Index* rows, std::size_t n) {
    return Aabb::split_direction(Aabb{}, positions, rows, n);
  }

  static constexpr std::size_t memory_bytes() { return sizeof(Sphere); }
};

}  // namespace surfeledit::bvh
