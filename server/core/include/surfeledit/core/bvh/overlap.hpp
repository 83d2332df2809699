// Overlap tests between box kinds and between a box and a surfel sphere (docs/algorithms.md §5, thesis
// Eqs. 8.4, 8.5, 8.7, 8.9-8.10, 9.1). Each returns true when the two volumes may overlap; false
// means they are certainly disjoint. Inline: they run in the traversal's hot path.
// Squared distances are named dist2.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>

#include "surfeledit/core/bvh/aabb.hpp"
#include "surfeledit/core/bvh/obb.hpp"
#include "surfeledit/core/bvh/sphere.hpp"
#include "surfeledit/core/enum_names.hpp"

namespace surfeledit::bvh {

// Which separating-axis test an OBB/AABB pair uses.
enum class SatMode : std::uint8_t {
  Lite = 0,  // 3 world + 3 OBB axes (van den Bergen's "SAT lite", Eqs. 8.9-8.10): conservative
  Full = 1,  // all 15 axes (Gottschalk): exact for boxes
};
constexpr EnumNames<SatMode, 2> names_of(SatMode) { return {{{SatMode::Lite, "lite"}, {SatMode::Full, "full"}}}; }
// Throws InvalidArgument naming `field` for a name not in names_of.
inline SatMode parse_sat(const std::string& name, const std::string& field = "sat") {
  return parse_enum<SatMode>(name, field);
}
inline const char* to_string(SatMode mode) { return enum_name(mode); }

// AABB / surfel sphere (Eq. 8.4): |b.center_d - s.center_d| <= b.ext_d + r on every axis, written
// with the corners. Conservative near the box edges (tests the box grown by r, not the rounded box).
inline bool overlap(const Aabb& b, const Sphere& s) {
  return (s.center.array() + s.radius >= b.lo.array()).all() && (s.center.array() - s.radius <= b.hi.array()).all();
}

// AABB / AABB (Eq. 8.5): the projections on every coordinate axis overlap. Exact.
inline bool overlap(const Aabb& a, const Aabb& b) {
  return (a.lo.array() <= b.hi.array()).all() && (b.lo.array() <= a.hi.array()).all();
}

// OBB / surfel sphere (Eq. 8.7): |(R (b.center - p))_d| <= b.ext_d + r on every box axis.
inline bool overlap(const Obb& b, const Sphere& s) {
  const Vec3 local = b.axes * (b.center - s.center);
  return (local.array().abs() <= b.ext.array() + s.radius).all();
}

// Sphere / sphere (Eq. 9.1): |c1 - c2|^2 <= (r1 + r2)^2. Exact.
inline bool overlap(const Sphere& a, const Sphere& b) {
  const double dist2 = (a.center - b.center).squaredNorm();
  const double reach = a.radius + b.radius;
  return dist2 <= reach * reach;
}

// Sphere / AABB: squared distance from the sphere centre to the box <= r^2. Exact.
inline bool overlap(const Sphere& s, const Aabb& b) {
  const Vec3 nearest = s.center.cwiseMax(b.lo).cwiseMin(b.hi);
  const double dist2 = (nearest - s.center).squaredNorm();
  return dist2 <= s.radius * s.radius;
}

// OBB / AABB, SAT lite (Eqs. 8.9-8.10). T = OBB centre - AABB centre, a = AABB half extents,
// b = OBB half extents, B_j = OBB axes (rows of `axes`). Separated if for a world axis d
//   |T_d| > a_d + sum_j b_j |B_j,d|
// or for an OBB axis j
//   |T . B_j| > sum_d a_d |B_j,d| + b_j.
inline bool overlap_sat_lite(const Obb& o, const Aabb& box) {
  const Vec3 a = box.half_extents();
  const Vec3 t = o.center - box.center();
  const Mat3 abs_r = o.axes.cwiseAbs();
  // World axes: the OBB's projection radius on axis d is sum_j b_j |B_j,d|.
  const Vec3 obb_radius_world = abs_r.transpose() * o.ext;
  if ((t.array().abs() > a.array() + obb_radius_world.array()).any()) return false;
  // OBB axes: the AABB's projection radius on B_j is sum_d a_d |B_j,d|.
  const Vec3 t_local = o.axes * t;
  const Vec3 box_radius_local = abs_r * a;
  return !(t_local.array().abs() > box_radius_local.array() + o.ext.array()).any();
}

// OBB / AABB with all 15 separating axes (the 6 of SAT lite plus the 9 cross products e_d x B_j).
// Exact up to rounding: reports an overlap iff the two solid boxes intersect (touching counts).
bool overlap_sat_full(const Obb& o, const Aabb& box);

// Box pairs of the tree/tree test (zero box kind first, deformable AABB second), one name for all.
inline bool overlap(const Aabb& zero, const Aabb& deformable, SatMode) { return overlap(zero, deformable); }
inline bool overlap(const Obb& zero, const Aabb& deformable, SatMode mode) {
  return mode == SatMode::Full ? overlap_sat_full(zero, deformable) : overlap_sat_lite(zero, deformable);
}
inline bool overlap(const Sphere& zero, const Aabb& deformable, SatMode) { return overlap(zero, deformable); }

// A surfel (its sphere) against a box of each kind.
inline bool overlap_surfel(const Aabb& b, const Sphere& surfel) { return overlap(b, surfel); }
inline bool overlap_surfel(const Obb& b, const Sphere& surfel) { return overlap(b, surfel); }
inline bool overlap_surfel(const Sphere& b, const Sphere& surfel) { return overlap(b, surfel); }

}  // namespace surfeledit::bvh
