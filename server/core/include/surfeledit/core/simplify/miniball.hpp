// Minimal enclosing spheres ("Miniball", Gaertner 1999; thesis §9.4.1) of points and of spheres,
// computed with CGAL's Min_sphere_of_spheres_d (CGAL stays inside the .cpp). The result is then
// grown, if rounding left any input poking out, until it contains every input exactly as
// bvh::Sphere::contains evaluates it. Model units.
#pragma once

#include <vector>

#include "surfeledit/core/bvh/sphere.hpp"

namespace surfeledit {

// Smallest sphere containing the points rows[0 .. n) of `positions`; empty sphere (radius < 0) if n = 0.
bvh::Sphere min_sphere_of_points(const Points& positions, const Index* rows, std::size_t n);
inline bvh::Sphere min_sphere_of_points(const Points& positions, const IndexList& rows) {
  return min_sphere_of_points(positions, rows.data(), rows.size());
}
// Smallest sphere containing the balls (positions[rows[k]], radii[rows[k]]) (the surfels' discs are
// inside these balls); `radii` may be empty (points).
bvh::Sphere min_sphere_of_balls(const Points& positions, const Values& radii, const Index* rows, std::size_t n);
// Smallest sphere containing the given spheres (empty ones are ignored).
bvh::Sphere min_sphere_of_spheres(const std::vector<bvh::Sphere>& spheres);
// Smallest sphere containing two spheres (closed form, no CGAL call).
bvh::Sphere min_sphere_of_two(const bvh::Sphere& a, const bvh::Sphere& b);

}  // namespace surfeledit
