// Helpers shared by the BVH tests: random clouds, invariant checks and brute-force references.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <string>

#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/bvh/obb.hpp"
#include "surfeledit/core/bvh/sphere.hpp"

namespace bvh_test {

using namespace surfeledit;
using namespace surfeledit::bvh;

// Points on a noisy, bumpy sheet (surface-like, as surfels are) plus radii ~ spacing.
inline void make_sheet(int n, std::uint64_t seed, Points& p, Values& r, double z0 = 0.0, double scale = 1.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  p.resize(n, 3);
  r.resize(n);
  const double spacing = 2.0 * scale / std::sqrt(double(n));
  for (int i = 0; i < n; ++i) {
    const double x = scale * u(rng), y = scale * u(rng);
    p.row(i) << x, y, z0 + 0.2 * scale * std::sin(3.0 * x) * std::cos(2.0 * y) + 0.01 * scale * u(rng);
    r[i] = spacing * (0.8 + 0.4 * (0.5 + 0.5 * u(rng)));
  }
}

inline IndexList all_rows(Index n) {
  IndexList rows(static_cast<std::size_t>(n));
  for (Index i = 0; i < n; ++i) rows[static_cast<std::size_t>(i)] = i;
  return rows;
}

// Every node contains the balls of its live surfels and its children; the slots are consistent.
template <class Box>
::testing::AssertionResult check_invariants(const Bvh<Box>& t, const Points& p, const Values& r) {
  for (std::size_t k = 0; k < t.nodes().size(); ++k) {
    const auto& nd = t.nodes()[k];
    bool ok = true;
    Index bad = -1;
    t.for_each_row(static_cast<std::int32_t>(k), [&](Index row) {
      if (ok && !nd.box.contains(p.row(row).transpose(), radius_of(r, row))) {
        ok = false;
        bad = row;
      }
    });
    if (!ok)
      return ::testing::AssertionFailure() << "node " << k << " (level " << nd.level << ") misses row " << bad;
    if (!nd.leaf()) {
      for (int c = 0; c < 2; ++c) {
        const auto& ch = t.nodes()[static_cast<std::size_t>(nd.first_child + c)];
        if constexpr (Box::kContainsChildren) {
          if (!nd.box.contains(ch.box)) return ::testing::AssertionFailure() << "node " << k << " misses child " << c;
        } else {
          if ((nd.box.ext.array() < ch.box.ext.array()).any())
            return ::testing::AssertionFailure() << "node " << k << " smaller than child " << c;
        }
        if (ch.parent != static_cast<std::int32_t>(k)) return ::testing::AssertionFailure() << "bad parent link at " << k;
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Random rotation (uniform quaternion).
inline Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  q.normalize();
  return q.toRotationMatrix();
}

}  // namespace bvh_test
