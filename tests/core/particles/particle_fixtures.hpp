// Shared particle configurations for the particle engine tests and benchmark: jittered planar patches and
// Fibonacci spheres (deterministic for a seed).
#pragma once

#include <cmath>
#include <random>

#include "surfeledit/core/particles/state.hpp"

namespace surfeledit::test {

// side x side particles on z = 0 with spacing 1, positions jittered by `jitter` in-plane and `lift` in z,
// normals tilted by up to `tilt` (radians-ish). Returns positions and normals.
inline ParticleState plane_patch(int side, double jitter, double lift, double tilt, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points x(side * side, 3), n(side * side, 3);
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b) {
      const int i = a * side + b;
      x.row(i) << a + jitter * u(rng), b + jitter * u(rng), lift * u(rng);
      n.row(i) << tilt * u(rng), tilt * u(rng), 1.0;
    }
  return ParticleState::from_surfels(x, n);
}

// `count` points on the sphere of radius `radius` about the origin, outward normals.
inline void fibonacci_sphere(int count, double radius, Points& x, Points& n) {
  x.resize(count, 3);
  n.resize(count, 3);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / count, rho = std::sqrt(1.0 - z * z), phi = golden * i;
    n.row(i) << rho * std::cos(phi), rho * std::sin(phi), z;
    x.row(i) = radius * n.row(i);
  }
}

}  // namespace surfeledit::test
