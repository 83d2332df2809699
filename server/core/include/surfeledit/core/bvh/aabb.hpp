// Axis-aligned bounding box (thesis §8.1): the box kind of the deformable tree and one choice for
// the zero region. Stored as its corners lo/hi (model units); centre and half extents (`ext` in
// Eqs. 8.4, 8.5) are derived. The corner form makes containment exact (no rounding) and lets a
// refit recompute single axes (the per-axis masks of thesis §8.3.1).
//
// A box bounds the *balls* of its surfels: every surfel (position p, radius r) lies in the box with
// its whole sphere, so a surfel sphere touching another surfel sphere always touches its box.
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include "surfeledit/core/types.hpp"

namespace surfeledit::bvh {

// Radius of row i, 0 when no radii were given (`radii.size() == 0`).
inline double radius_of(const Values& radii, Index i) { return radii.size() ? radii[i] : 0.0; }

// Marks a slot of a tree's row permutation whose surfel was removed.
constexpr Index kDeadRow = -1;

struct Aabb {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());   // min corner, model units
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());  // max corner, model units

  bool empty() const { return (lo.array() > hi.array()).any(); }
  Vec3 center() const { return 0.5 * (lo + hi); }
  Vec3 half_extents() const { return 0.5 * (hi - lo); }

  // Grows to contain the ball (p, r).
  void expand(const Vec3& p, double r) {
    lo = lo.cwiseMin((p.array() - r).matrix());
    hi = hi.cwiseMax((p.array() + r).matrix());
  }
  // Grows to contain another box.
  void expand(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  void enclose(const Aabb& child) { expand(child); }
  // A parent's box after the build: contains its children (thesis §10.1.1, "at least as large").
  static constexpr bool kContainsChildren = true;
  void grow_over_child(const Aabb& child) { enclose(child); }
  // Adds a margin of `m` model units on every side.
  void inflate(double m) {
    lo.array() -= m;
    hi.array() += m;
  }
  // Widens every axis to at least `extent` model units, around the current centre (thesis §10.1.1).
  void enforce_min_extent(double extent) {
    for (int d = 0; d < 3; ++d) {
      const double w = hi[d] - lo[d];
      if (w < extent) {
        const double grow = 0.5 * (extent - w);
        lo[d] -= grow;
        hi[d] += grow;
      }
    }
  }
  bool contains(const Vec3& p, double r) const {
    return (p.array() - r >= lo.array()).all() && (p.array() + r <= hi.array()).all();
  }
  bool contains(const Aabb& b) const {
    return (b.lo.array() >= lo.array()).all() && (b.hi.array() <= hi.array()).all();
  }

  // Tight box over the balls of `rows[0..n)` (slots holding kDeadRow are skipped).
  static Aabb fit(const Points& positions, const Values& radii, const Index* rows, std::size_t n) {
    Aabb b;
    for (std::size_t k = 0; k < n; ++k) {
      const Index i = rows[k];
      if (i < 0) continue;
      b.expand(positions.row(i).transpose(), radius_of(radii, i));
    }
    return b;
  }
  // Split direction of the top-down build: the coordinate axis along which the positions spread
  // most (largest variance, "splatter", thesis §8.1.1).
  static Vec3 split_direction(const Aabb&, const Points& positions, const Index* rows, std::size_t n) {
    Vec3 sum = Vec3::Zero(), sum2 = Vec3::Zero();
    for (std::size_t k = 0; k < n; ++k) {
      const Vec3 p = positions.row(rows[k]).transpose();
      sum += p;
      sum2 += p.cwiseProduct(p);
    }
    const Vec3 var = sum2 / double(n) - (sum / double(n)).cwiseAbs2();
    int axis = 0;
    var.maxCoeff(&axis);
    return Vec3::Unit(axis);
  }

  static constexpr std::size_t memory_bytes() { return sizeof(Aabb); }
};

}  // namespace surfeledit::bvh
