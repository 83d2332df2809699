// Oriented bounding box (thesis §8.2): axes = eigenvectors of the covariance of the surfel
// positions (PCA, Eq. 8.6), sorted by decreasing variance; extents from projecting the surfel balls.
// `axes` is the rotation R of Eq. 8.7: its rows are the unit box axes, R (p - center) gives a point
// in the box frame. Model units throughout.
#pragma once

#include <cstddef>

#include "surfeledit/core/bvh/aabb.hpp"

namespace surfeledit::bvh {

struct Obb {
  Vec3 center = Vec3::Zero();                          // model units
  Vec3 ext = Vec3::Constant(-1.0);                     // half extents along the rows of `axes`; < 0 = empty
  Mat3 axes = Mat3::Identity();                        // rows: unit axes, row 0 = largest variance

  bool empty() const { return ext[0] < 0.0; }
  Vec3 to_local(const Vec3& p) const { return axes * (p - center); }

  // Grows (axes kept) to contain the ball (p, r).
  void expand(const Vec3& p, double r);
  // Grows (axes kept) to contain the 8 corners of a child box.
  void enclose(const Obb& child);
  // thesis §10.1.1 for OBBs: a parent is at least as large as its children (half extents at least the
  // children's, axis by axis in variance order), but is NOT grown to contain their corners: a child
  // turned against its parent overhangs at the corners, and enclosing them level by level inflated
  // the root of a 3 x 3 slab to half extents of ~6.7 instead of ~2.1. Correctness needs only that
  // every node contains its own surfels, which the fit guarantees.
  static constexpr bool kContainsChildren = false;
  void grow_over_child(const Obb& child) { ext = ext.cwiseMax(child.ext); }
  void inflate(double m) { ext.array() += m; }
  // Every axis at least `extent` wide (thesis §10.1.1).
  void enforce_min_extent(double extent) { ext = ext.cwiseMax(Vec3::Constant(0.5 * extent)); }
  // Containment with a relative tolerance of 1e-9 of the box size (the fit pads by about 1e-12).
  bool contains(const Vec3& p, double r) const;
  bool contains(const Obb& child) const;

  // PCA fit over the balls of rows[0..n) (kDeadRow skipped).
  static Obb fit(const Points& positions, const Values& radii, const Index* rows, std::size_t n);
  // The principal axis (row 0 of the fitted box's axes, thesis §8.2.1).
  static Vec3 split_direction(const Obb& box, const Points&, const Index*, std::size_t) {
    return box.axes.row(0).transpose();
  }

  static constexpr std::size_t memory_bytes() { return sizeof(Obb); }
};

}  // namespace surfeledit::bvh
