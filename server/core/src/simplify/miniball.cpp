// Minimal enclosing spheres via CGAL's Min_sphere_of_spheres_d (Debian libcgal-dev, header-only),
// with its floating-point square-root arithmetic (Tag_true), followed by an exact containment fix-up.
#include "surfeledit/core/simplify/miniball.hpp"

#include <array>

// GCC 12 reports a false -Wstringop-overflow inside std::vector::insert as inlined into CGAL.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wstringop-overflow"
#include <CGAL/Min_sphere_of_spheres_d.h>

namespace surfeledit {

namespace {

struct Ball {
  std::array<double, 3> c;  // centre
  double r;                 // radius >= 0
};

// The traits concept of Min_sphere_of_spheres_d for our ball type.
struct BallTraits {
  typedef double FT;
  typedef double Radius;
  typedef Ball Sphere;
  typedef const double* Cartesian_const_iterator;
  typedef CGAL::Tag_true Use_square_roots;
  typedef CGAL::Default_algorithm Algorithm;
  static const int D = 3;
  static const double& radius(const Ball& b) { return b.r; }
  static const double* center_cartesian_begin(const Ball& b) { return b.c.data(); }
};

// Solves, then grows the radius until every ball is inside as bvh::Sphere::contains evaluates it.
bvh::Sphere solve(const std::vector<Ball>& balls) {
  bvh::Sphere out;
  if (balls.empty()) return out;
  CGAL::Min_sphere_of_spheres_d<BallTraits> ms(balls.begin(), balls.end());
  const double* c = ms.center_cartesian_begin();
  out.center = Vec3(c[0], c[1], c[2]);
  out.radius = std::max(0.0, static_cast<double>(ms.radius()));
  for (const Ball& b : balls) {
    const double need = (Vec3(b.c[0], b.c[1], b.c[2]) - out.center).norm() + b.r;
    if (need > out.radius) out.radius = need;
  }
  return out;
}

}  // namespace

bvh::Sphere min_sphere_of_balls(const Points& positions, const Values& radii, const Index* rows, std::size_t n) {
  std::vector<Ball> balls(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Index r = rows[k];
    balls[k] = Ball{{positions(r, 0), positions(r, 1), positions(r, 2)}, radii.size() ? std::max(0.0, radii[r]) : 0.0};
  }
  return solve(balls);
}

bvh::Sphere min_sphere_of_points(const Points& positions, const Index* rows, std::size_t n) {
  return min_sphere_of_balls(positions, Values(), rows, n);
}

bvh::Sphere min_sphere_of_spheres(const std::vector<bvh::Sphere>& spheres) {
  std::vector<Ball> balls;
  balls.reserve(spheres.size());
  for (const bvh::Sphere& s : spheres)
    if (!s.empty()) balls.push_back(Ball{{s.center.x(), s.center.y(), s.center.z()}, s.radius});
  return solve(balls);
}

bvh::Sphere min_sphere_of_two(const bvh::Sphere& a, const bvh::Sphere& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  const Vec3 d = b.center - a.center;
  const double dist = d.norm();
  if (dist + b.radius <= a.radius) return a;
  if (dist + a.radius <= b.radius) return b;
  bvh::Sphere out;
  out.radius = 0.5 * (dist + a.radius + b.radius);
  out.center = a.center + d * ((out.radius - a.radius) / dist);
  // Rounding fix-up, as for the CGAL results.
  out.radius = std::max({out.radius, (a.center - out.center).norm() + a.radius, (b.center - out.center).norm() + b.radius});
  return out;
}

}  // namespace surfeledit

#pragma GCC diagnostic pop
