// Overlap tests of the BVH box kinds against brute-force references on random boxes and spheres
// (issue 4): full SAT exact, SAT lite never "separated" for overlapping boxes (and how often it is
// conservatively wrong), AABB/AABB, sphere/sphere, surfel/box tests, and the fits.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <random>

#include "bvh_test_util.hpp"
#include "surfeledit/core/bvh/overlap.hpp"

namespace {

using namespace bvh_test;

std::array<Vec3, 8> corners(const Vec3& c, const Mat3& axes_rows, const Vec3& ext) {
  std::array<Vec3, 8> out;
  for (int k = 0; k < 8; ++k) {
    Vec3 l;
    for (int d = 0; d < 3; ++d) l[d] = (k >> d & 1) ? ext[d] : -ext[d];
    out[static_cast<std::size_t>(k)] = c + axes_rows.transpose() * l;
  }
  return out;
}

// Reference: enumerate the 15 candidate axes (3 + 3 face normals, 9 edge cross products) and project
// all 8 corners of each box on each. Returns the largest gap between the projected intervals over
// all axes, normalised by the axis length (> 0: separated by that distance, <= 0: overlapping).
double separation_brute(const Obb& o, const Aabb& a) {
  const auto co = corners(o.center, o.axes, o.ext);
  const auto ca = corners(a.center(), Mat3::Identity(), a.half_extents());
  std::vector<Vec3> axes;
  for (int d = 0; d < 3; ++d) axes.push_back(Vec3::Unit(d));
  for (int j = 0; j < 3; ++j) axes.push_back(o.axes.row(j).transpose());
  for (int d = 0; d < 3; ++d)
    for (int j = 0; j < 3; ++j) {
      const Vec3 l = Vec3::Unit(d).cross(o.axes.row(j).transpose());
      if (l.norm() > 1e-9) axes.push_back(l.normalized());
    }
  double best = -1e300;
  for (const Vec3& l : axes) {
    double omin = 1e300, omax = -1e300, amin = 1e300, amax = -1e300;
    for (const Vec3& c : co) {
      omin = std::min(omin, c.dot(l));
      omax = std::max(omax, c.dot(l));
    }
    for (const Vec3& c : ca) {
      amin = std::min(amin, c.dot(l));
      amax = std::max(amax, c.dot(l));
    }
    best = std::max(best, std::max(amin - omax, omin - amax));
  }
  return best;
}

Obb random_obb(std::mt19937_64& rng, double spread) {
  std::uniform_real_distribution<double> u(-spread, spread), e(0.05, 1.0);
  Obb o;
  o.center = Vec3(u(rng), u(rng), u(rng));
  o.ext = Vec3(e(rng), e(rng), e(rng));
  o.axes = random_rotation(rng);
  return o;
}

Aabb random_aabb(std::mt19937_64& rng, double spread) {
  std::uniform_real_distribution<double> u(-spread, spread), e(0.05, 1.0);
  const Vec3 c(u(rng), u(rng), u(rng)), h(e(rng), e(rng), e(rng));
  Aabb a;
  a.lo = c - h;
  a.hi = c + h;
  return a;
}

void sat_experiment(double spread, const char* label) {
  std::mt19937_64 rng(4242);
  const int n = 200000;
  int overlapping = 0, separated = 0, lite_wrong = 0, full_wrong = 0, near = 0;
  for (int i = 0; i < n; ++i) {
    const Obb o = random_obb(rng, spread);
    const Aabb a = random_aabb(rng, 0.0);  // AABB at the origin: the OBB carries the offset
    const double gap = separation_brute(o, a);
    const bool full = overlap_sat_full(o, a);
    const bool lite = overlap_sat_lite(o, a);
    if (std::abs(gap) < 1e-9) {  // touching within rounding: either answer is right
      ++near;
      continue;
    }
    const bool truth = gap <= 0.0;
    if (truth) {
      ++overlapping;
      ASSERT_TRUE(lite) << "SAT lite reported separated for overlapping boxes, case " << i;
    } else {
      ++separated;
      if (lite) ++lite_wrong;
    }
    if (full != truth) ++full_wrong;
  }
  EXPECT_EQ(full_wrong, 0);
  const double rate_all = double(lite_wrong) / double(overlapping + separated);
  const double rate_sep = double(lite_wrong) / double(separated);
  std::printf("[ SAT lite ] %s: %d random OBB/AABB pairs (half extents 0.05..1, OBB centre uniform in +-%.1f^3): "
              "%d overlapping, %d separated, %d touching (skipped)\n",
              label, n, spread, overlapping, separated, near);
  std::printf("[ SAT lite ] conservatively wrong (overlap reported, boxes disjoint): %d = %.2f%% of all tests, "
              "%.2f%% of the disjoint pairs (thesis/van den Bergen: ~6%%)\n",
              lite_wrong, 100.0 * rate_all, 100.0 * rate_sep);
  EXPECT_GT(overlapping, n / 10);
  EXPECT_GT(separated, n / 10);
}

TEST(BvhOverlap, FullSatIsExactAndLiteIsConservative) {
  sat_experiment(2.0, "sparse");
  sat_experiment(1.2, "dense");  // more pairs close to contact, as deep in a tree/tree traversal
}

TEST(BvhOverlap, IdentityObbMatchesAabbTest) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const Aabb a = random_aabb(rng, 1.5), b = random_aabb(rng, 1.5);
    Obb o;
    o.center = b.center();
    o.ext = b.half_extents();
    o.axes = Mat3::Identity();
    ASSERT_EQ(overlap(a, b), overlap_sat_full(o, a)) << i;
    ASSERT_EQ(overlap(a, b), overlap_sat_lite(o, a)) << i;  // for aligned boxes lite is exact
    // Brute force for the AABB pair: the intervals overlap on all 3 axes.
    bool brute = true;
    for (int d = 0; d < 3; ++d) brute &= a.lo[d] <= b.hi[d] && b.lo[d] <= a.hi[d];
    ASSERT_EQ(overlap(a, b), brute);
    ASSERT_EQ(overlap(a, b), overlap(b, a));
  }
}

TEST(BvhOverlap, SphereAndSurfelTests) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-2.0, 2.0), rr(0.01, 0.8);
  int aabb_conservative = 0, obb_conservative = 0;
  for (int i = 0; i < 50000; ++i) {
    const Sphere s{Vec3(u(rng), u(rng), u(rng)), rr(rng)};
    const Sphere t{Vec3(u(rng), u(rng), u(rng)), rr(rng)};
    // Sphere/sphere (Eq. 9.1) vs the distance itself.
    ASSERT_EQ(overlap(s, t), (s.center - t.center).norm() <= s.radius + t.radius) << i;

    // AABB/surfel (Eq. 8.4): conservative; exact distance via the clamped point.
    const Aabb a = random_aabb(rng, 1.0);
    Vec3 q = s.center;
    for (int d = 0; d < 3; ++d) q[d] = std::min(std::max(q[d], a.lo[d]), a.hi[d]);
    const bool exact = (q - s.center).norm() <= s.radius;
    if (exact) ASSERT_TRUE(overlap_surfel(a, s)) << i;
    if (overlap_surfel(a, s) && !exact) ++aabb_conservative;
    ASSERT_EQ(overlap(s, a), exact) << i;  // sphere box kind / AABB: exact

    // OBB/surfel (Eq. 8.7): conservative, exact reference in the box frame.
    const Obb o = random_obb(rng, 1.0);
    const Vec3 local = o.to_local(s.center);
    const Vec3 clamped = local.cwiseMax(-o.ext).cwiseMin(o.ext);
    const bool exact_o = (clamped - local).norm() <= s.radius;
    if (exact_o) ASSERT_TRUE(overlap_surfel(o, s)) << i;
    if (overlap_surfel(o, s) && !exact_o) ++obb_conservative;
  }
  std::printf("[ surfel  ] Eq. 8.4 / 8.7 conservative reports (box corners): AABB %d, OBB %d of 50000\n",
              aabb_conservative, obb_conservative);
}

TEST(BvhOverlap, FitsContainTheirBalls) {
  Points p;
  Values r;
  make_sheet(3000, 5, p, r);
  // Tilt the sheet so that the OBB has work to do.
  std::mt19937_64 rng(5);
  const Mat3 rot = random_rotation(rng);
  p = (p * rot.transpose()).eval();
  const IndexList rows = all_rows(static_cast<Index>(p.rows()));
  const Aabb a = Aabb::fit(p, r, rows.data(), rows.size());
  const Obb o = Obb::fit(p, r, rows.data(), rows.size());
  const Sphere s = Sphere::fit(p, r, rows.data(), rows.size());
  for (Index i = 0; i < p.rows(); ++i) {
    ASSERT_TRUE(a.contains(p.row(i).transpose(), r[i]));
    ASSERT_TRUE(o.contains(p.row(i).transpose(), r[i]));
    ASSERT_TRUE(s.contains(p.row(i).transpose(), r[i]));
  }
  // The OBB's smallest axis is the sheet's normal (the rotated z axis), up to sign and the bumps.
  EXPECT_GT(std::abs(o.axes.row(2).dot(rot.col(2))), 0.9);
  EXPECT_NEAR(o.axes.determinant(), 1.0, 1e-9);
  // PCA fits the tilted sheet tighter than the AABB.
  EXPECT_LT(o.ext.prod(), a.half_extents().prod());
  // Memory per box kind (thesis: AABB 28 bytes with floats + child pointer; ours doubles).
  std::printf("[ memory  ] bytes per box: AABB %zu, OBB %zu, sphere %zu\n", Aabb::memory_bytes(),
              Obb::memory_bytes(), Sphere::memory_bytes());
}

TEST(BvhOverlap, Names) {
  EXPECT_EQ(parse_sat("lite"), SatMode::Lite);
  EXPECT_EQ(parse_sat("full"), SatMode::Full);
  EXPECT_THROW(parse_sat("half"), Error);
  EXPECT_STREQ(to_string(SatMode::Full), "full");
}

}  // namespace
