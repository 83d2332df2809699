// The deformation tests' models: a sampled capsule with tangent axes and regions (test_deformation.cpp,
// test_deformation_step.cpp), a sphere over a slab with random tangent axes (the kernels' bit-for-bit tests), and
// independent truth: brute-force region distances and lambda, the step map written without the library, F1's
// centroid.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit::deformation_model {

// A capsule along z (radius 0.4, half length 0.8): bottom (z < -0.3) is F0, top (z > 0.3) is F1.
struct Model {
  Points positions, normals, tu, tv;  // #P by 3
  std::vector<Region> regions;        // #P
};

inline Model make_model(double spacing = 0.04, double z0 = -0.3, double z1 = 0.3) {
  SampleParams sp;
  sp.spacing = spacing;
  sp.seed = 7;
  const SampledSurfels s = make_capsule(0.4, 0.8)->sample(sp);
  Model m;
  m.positions = s.positions;
  m.normals = s.normals;
  m.tu.resize(s.positions.rows(), 3);
  m.tv.resize(s.positions.rows(), 3);
  for (Eigen::Index i = 0; i < s.positions.rows(); ++i) {
    const Vec3 n = s.normals.row(i).transpose();
    const Vec3 u = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
    m.tu.row(i) = (spacing * u).transpose();
    m.tv.row(i) = (spacing * n.cross(u)).transpose();
    const double z = s.positions(i, 2);
    m.regions.push_back(z < z0 ? Region::Zero : (z > z1 ? Region::One : Region::Blend));
  }
  return m;
}

// A sphere (radius 0.5, centre 0.8 above the origin) over a slab (half extents 0.8, 0.8, 0.1), both sampled at
// spacing 0.03: the slab's `slab_rows` rows first, region Zero, then the sphere's, region One (callers re-mark
// them). The tangent axes are random, uniform in [-0.02, 0.02) per coordinate from `seed`, so that every lane of
// a vector kernel sees different values.
inline Model sphere_over_slab(unsigned seed, Eigen::Index* slab_rows = nullptr) {
  Pose above;
  above.translation = Vec3(0.0, 0.0, 0.8);
  const SampledSurfels s = make_sphere(0.5, above)->sample(SampleParams{0.03, 11, 0.25});
  const SampledSurfels b = make_box(Vec3(0.8, 0.8, 0.1))->sample(SampleParams{0.03, 11, 0.25});
  Model m;
  const Eigen::Index nb = b.positions.rows(), n = nb + s.positions.rows();
  m.positions.resize(n, 3);
  m.normals.resize(n, 3);
  m.positions << b.positions, s.positions;
  m.normals << b.normals, s.normals;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  m.tu.resize(n, 3);
  m.tv.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j) m.tu(i, j) = u(rng), m.tv(i, j) = u(rng);
  m.regions.assign(static_cast<std::size_t>(nb), Region::Zero);
  m.regions.resize(static_cast<std::size_t>(n), Region::One);
  if (slab_rows) *slab_rows = nb;
  return m;
}

// Whether two #P by 3 arrays hold the same doubles, bit for bit.
inline bool same_bits(const Points& x, const Points& y) {
  return x.rows() == y.rows() &&
         std::memcmp(x.data(), y.data(), sizeof(double) * static_cast<std::size_t>(x.size())) == 0;
}

// Brute-force distances (model units, not squared) from x to the nearest row of region r.
inline double brute_distance(const Model& m, const Vec3& x, Region r, Index* which = nullptr) {
  double best = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < m.positions.rows(); ++i) {
    if (m.regions[static_cast<std::size_t>(i)] != r) continue;
    const double d = (m.positions.row(i).transpose() - x).norm();
    if (d < best) {
      best = d;
      if (which) *which = static_cast<Index>(i);
    }
  }
  return best;
}

inline double brute_lambda(const Model& m, const Vec3& x) {
  const double d0 = brute_distance(m, x, Region::Zero), d1 = brute_distance(m, x, Region::One);
  return d0 / (d0 + d1);
}

// The step map written independently of the library: R(a, s alpha)(x - c) + c + s t.
inline Vec3 reference_map(const Vec3& x, double s, const DeformParams& p, const Vec3& c) {
  const Mat3 r = Eigen::AngleAxisd(s * p.angle, p.axis.normalized()).toRotationMatrix();
  return r * (x - c) + c + s * p.translation;
}

inline Vec3 f1_centroid(const Model& m) {
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (Eigen::Index i = 0; i < m.positions.rows(); ++i) {
    if (m.regions[static_cast<std::size_t>(i)] == Region::One) {
      sum += m.positions.row(i).transpose();
      ++n;
    }
  }
  return sum / n;
}

}  // namespace surfeledit::deformation_model
