// The compact encoding of update surfels (update_compact.hpp): octahedral normals against the exact
// unit vectors they encode, float32 offsets against the doubles, at large offsets and small extents.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "surfeledit/service/update_compact.hpp"

using namespace surfeledit::service;

namespace {

// The angle between unit vectors a and b, accurate near zero (atan2 of the cross and dot products).
double angle(const double a[3], const std::array<double, 3>& b) {
  const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  return std::atan2(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
}

template <typename T>
T read_le(const std::vector<std::uint8_t>& blob, std::size_t index) {
  T v;
  std::memcpy(&v, blob.data() + index * sizeof(T), sizeof(T));  // the tests run on little-endian machines
  return v;
}

}  // namespace

TEST(OctahedralNormals, RandomUnitVectorsDecodeWithinTheStatedAngle) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  double worst = 0.0;
  for (int i = 0; i < 1000000; ++i) {
    double n[3] = {g(rng), g(rng), g(rng)};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& x : n) x /= len;
    worst = std::max(worst, angle(n, octahedral_decode(octahedral_encode(n))));
  }
  EXPECT_LE(worst, kOctahedralMaxAngle);
  EXPECT_GT(worst, 0.1 * kOctahedralMaxAngle);  // the bound is not loose by orders of magnitude
}

TEST(OctahedralNormals, AxesEdgesAndSignedZerosAreExactOrWithinTheAngle) {
  const double s = 1.0 / std::sqrt(2.0), t = 1.0 / std::sqrt(3.0);
  const double cases[][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0}, {0, 0, 1},  {0, 0, -1},
                             {s, s, 0},  {-s, s, 0}, {s, -s, 0},  {-s, -s, 0}, {t, t, -t}, {-t, -t, -t},
                             {0, s, -s}, {-0.0, 0, -1}, {s, 0, -s}, {0, -0.0, 1}};
  for (const auto& n : cases) {
    const auto back = octahedral_decode(octahedral_encode(n));
    EXPECT_LE(angle(n, back), kOctahedralMaxAngle) << n[0] << " " << n[1] << " " << n[2];
  }
  for (int a = 0; a < 3; ++a) {  // the six axes decode exactly
    for (double sign : {1.0, -1.0}) {
      double n[3] = {0, 0, 0};
      n[a] = sign;
      const auto back = octahedral_decode(octahedral_encode(n));
      EXPECT_EQ(back[static_cast<std::size_t>(a)], sign);
    }
  }
}

TEST(CompactSurfels, OffsetsFromThePartsCentreKeepTheStatedPositionBound) {
  // A part far from the origin with a small extent: the bound is relative to the extent, not the offset.
  for (double offset : {0.0, 1e6}) {
    for (double extent : {1e-4, 1.0, 1e4}) {
      PreparedUpdate u;
      std::mt19937_64 rng(11);
      std::uniform_real_distribution<double> d(0.0, extent);
      const std::size_t n = 2000;
      for (std::size_t k = 0; k < n; ++k) {
        u.ids.push_back(k);
        for (int a = 0; a < 3; ++a) u.positions.push_back(offset + d(rng));
        u.normals.insert(u.normals.end(), {0.0, 0.0, 1.0});
        u.radii.push_back(extent * (0.01 + 1e-3 * static_cast<double>(k)));
      }
      const std::size_t begin = 100, count = 1500;
      const CompactSurfels c = encode_compact(u, begin, count);
      ASSERT_EQ(c.positions.size(), count * 12);
      ASSERT_EQ(c.normals.size(), count * 4);
      ASSERT_EQ(c.radii.size(), count * 4);
      for (std::size_t k = 0; k < count; ++k) {
        for (std::size_t a = 0; a < 3; ++a) {
          const double truth = u.positions[3 * (begin + k) + a];
          const double back = c.origin[a] + static_cast<double>(read_le<float>(c.positions, 3 * k + a));
          EXPECT_LE(std::abs(back - truth), std::ldexp(extent, -25) + std::ldexp(std::abs(truth), -52) * 2)
              << "offset " << offset << " extent " << extent << " surfel " << k;
        }
        const double r = u.radii[begin + k];
        EXPECT_LE(std::abs(static_cast<double>(read_le<float>(c.radii, k)) - r), std::ldexp(r, -24));
      }
    }
  }
}

TEST(CompactSurfels, AnEmptyPartAndARangeBeyondTheUpdate) {
  PreparedUpdate u;
  const CompactSurfels empty = encode_compact(u, 0, 0);
  EXPECT_TRUE(empty.positions.empty());
  EXPECT_THROW(encode_compact(u, 0, 1), std::out_of_range);
}
