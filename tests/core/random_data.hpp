// Seeded random inputs shared by the core tests: point clouds and surfel arrays.
#pragma once

#include <cstdint>
#include <random>

#include "surfeledit/core/surfel_model.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::test {

// #n by 3 points uniform in the cube offset + scale * [-1, 1]^3 (mt19937_64 seeded with `seed`).
inline Points uniform_cloud(int n, std::uint64_t seed, double scale, const Vec3& offset) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points p(n, 3);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) p(i, d) = offset[d] + scale * u(rng);
  return p;
}

// n surfels in [-1, 1]^3: normals never zero (z = 2 before normalisation), radii in [0.01, 0.03].
inline SurfelArrays random_arrays(Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SurfelArrays a;
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  a.radii.resize(n);
  for (Index i = 0; i < n; ++i) {
    a.positions.row(i) << u(rng), u(rng), u(rng);
    a.normals.row(i) << u(rng), u(rng), 2.0;
    a.radii[i] = 0.01 + 0.01 * (u(rng) + 1.0);
  }
  return a;
}

}  // namespace surfeledit::test
