// select_rows and validate(Selector): random clouds against a brute-force truth written out per
// coordinate, the boundary (included) and the typed errors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "expect_error.hpp"
#include "surfeledit/core/selector.hpp"

namespace surfeledit {
namespace {

Points selector_cloud(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  Points p(n, 3);
  for (int i = 0; i < n; ++i) p.row(i) << u(rng), u(rng), u(rng);
  return p;
}

Selector sphere(const Vec3& c, double r) {
  Selector s;
  s.kind = Selector::Kind::Sphere;
  s.center = c;
  s.radius = r;
  return s;
}

Selector box(const Vec3& c, const Vec3& half) {
  Selector s;
  s.kind = Selector::Kind::Box;
  s.center = c;
  s.half_extents = half;
  return s;
}

TEST(Selector, SphereMatchesBruteForce) {
  const Points p = selector_cloud(5000, 1);
  const Vec3 c(0.3, -0.2, 0.5);
  const double r = 1.1;
  IndexList truth;
  for (Index i = 0; i < p.rows(); ++i) {
    const double dx = p(i, 0) - c.x(), dy = p(i, 1) - c.y(), dz = p(i, 2) - c.z();
    if (std::sqrt(dx * dx + dy * dy + dz * dz) <= r) truth.push_back(i);
  }
  EXPECT_GT(truth.size(), 100u);
  EXPECT_EQ(select_rows(p, sphere(c, r)), truth);
}

TEST(Selector, BoxMatchesBruteForce) {
  const Points p = selector_cloud(5000, 2);
  const Vec3 c(-0.4, 0.1, 0.0), half(0.5, 1.0, 1.5);
  IndexList truth;
  for (Index i = 0; i < p.rows(); ++i) {
    bool in = true;
    for (int d = 0; d < 3; ++d) in = in && std::fabs(p(i, d) - c[d]) <= half[d];
    if (in) truth.push_back(i);
  }
  EXPECT_GT(truth.size(), 100u);
  EXPECT_EQ(select_rows(p, box(c, half)), truth);
}

TEST(Selector, BoundaryIsIncludedAndZeroSizeSelectsExactHits) {
  Points p(5, 3);
  p << 1, 0, 0,  //
      0, -1, 0,  //
      1 + 1e-12, 0, 0,  //
      1, -2, 3,  //
      1, 2, 3.0000001;
  EXPECT_EQ(select_rows(p, sphere(Vec3::Zero(), 1.0)), (IndexList{0, 1}));
  EXPECT_EQ(select_rows(p, box(Vec3::Zero(), Vec3(1, 2, 3))), (IndexList{0, 1, 3}));
  EXPECT_EQ(select_rows(p, sphere(Vec3(1, 0, 0), 0.0)), (IndexList{0}));
  EXPECT_EQ(select_rows(p, box(Vec3(1, -2, 3), Vec3::Zero())), (IndexList{3}));
  EXPECT_TRUE(select_rows(Points(0, 3), sphere(Vec3::Zero(), 5.0)).empty());
}

void expect_invalid(const Selector& s, const std::string& field) {
  testing_util::expect_error([&] { validate(s, "sel"); }, ErrorCode::InvalidArgument, field);
}

TEST(Selector, ValidateNamesTheBadField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_NO_THROW(validate(sphere(Vec3::Zero(), 0.0), "sel"));
  EXPECT_NO_THROW(validate(box(Vec3(1, 2, 3), Vec3::Zero()), "sel"));
  expect_invalid(sphere(Vec3::Zero(), -1e-9), "sel.radius");
  expect_invalid(sphere(Vec3::Zero(), nan), "sel.radius");
  expect_invalid(sphere(Vec3::Zero(), inf), "sel.radius");
  expect_invalid(sphere(Vec3(0, nan, 0), 1.0), "sel.center");
  expect_invalid(box(Vec3::Zero(), Vec3(1, -1, 1)), "sel.half_extents");
  expect_invalid(box(Vec3::Zero(), Vec3(1, 1, inf)), "sel.half_extents");
  Selector bad = sphere(Vec3::Zero(), 1.0);
  bad.kind = static_cast<Selector::Kind>(7);
  expect_invalid(bad, "sel.kind");
}

}  // namespace
}  // namespace surfeledit
