// Minimal enclosing spheres (CGAL behind miniball.hpp) against an independent brute force: the
// smallest of all spheres internally tangent to a subset of at most 4 input balls (centre in the affine
// hull of the subset's centres) that contains every ball. Points are balls of radius 0. Covers 1-4
// points, duplicates, coplanar and collinear points, and spheres of different radii.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <limits>
#include <random>

#include "surfeledit/core/simplify/miniball.hpp"

namespace surfeledit {
namespace {

struct Ball {
  Vec3 c;
  double r;
};

// Balls tangent from inside to every ball of `s` (|x - c_i| = R - r_i, x in the affine hull of the
// c_i): the differences of those equations are linear in (x, R); the first one is then a quadratic in R.
std::vector<Ball> tangent_balls(const std::vector<Ball>& s) {
  std::vector<Ball> out;
  const int m = static_cast<int>(s.size());
  if (m == 1) return {s[0]};
  Eigen::MatrixXd e(3, m - 1);
  for (int j = 1; j < m; ++j) e.col(j - 1) = s[j].c - s[0].c;
  const Eigen::MatrixXd g = e.transpose() * e;
  Eigen::FullPivLU<Eigen::MatrixXd> lu(g);
  if (lu.rank() < m - 1) return out;  // affinely dependent centres: a smaller subset covers it
  Eigen::VectorXd b(m - 1), gr(m - 1);
  for (int k = 1; k < m; ++k) {
    b[k - 1] = 0.5 * (e.col(k - 1).squaredNorm() - s[k].r * s[k].r + s[0].r * s[0].r);
    gr[k - 1] = s[k].r - s[0].r;
  }
  // alpha = a0 + R a1; d = x - c0 = E alpha = u + R v; |d|^2 = (R - r0)^2.
  const Vec3 u = e * lu.solve(b), v = e * lu.solve(gr);
  const double qa = v.squaredNorm() - 1.0, qb = 2.0 * (u.dot(v) + s[0].r), qc = u.squaredNorm() - s[0].r * s[0].r;
  std::vector<double> roots;
  if (std::abs(qa) < 1e-14) {
    if (std::abs(qb) > 1e-14) roots.push_back(-qc / qb);
  } else {
    const double disc = qb * qb - 4 * qa * qc;
    if (disc >= -1e-12) {
      const double sq = std::sqrt(std::max(0.0, disc));
      roots.push_back((-qb + sq) / (2 * qa));
      roots.push_back((-qb - sq) / (2 * qa));
    }
  }
  for (double r : roots) {
    bool ok = true;
    for (const Ball& bl : s) ok = ok && r >= bl.r - 1e-12;
    if (ok) out.push_back(Ball{s[0].c + u + r * v, r});
  }
  return out;
}

Ball brute_force(const std::vector<Ball>& balls) {
  const int n = static_cast<int>(balls.size());
  Ball best{Vec3::Zero(), std::numeric_limits<double>::infinity()};
  for (int mask = 1; mask < (1 << n); ++mask) {
    if (__builtin_popcount(mask) > 4) continue;
    std::vector<Ball> s;
    for (int i = 0; i < n; ++i)
      if (mask & (1 << i)) s.push_back(balls[i]);
    for (const Ball& cand : tangent_balls(s)) {
      bool all = true;
      for (const Ball& b : balls) all = all && (b.c - cand.c).norm() + b.r <= cand.r * (1 + 1e-9) + 1e-9;
      if (all && cand.r < best.r) best = cand;
    }
  }
  return best;
}

void expect_matches(const std::vector<Ball>& balls, const char* what) {
  std::vector<bvh::Sphere> spheres;
  Points p(static_cast<Eigen::Index>(balls.size()), 3);
  Values r(static_cast<Eigen::Index>(balls.size()));
  IndexList rows;
  for (std::size_t k = 0; k < balls.size(); ++k) {
    bvh::Sphere s;
    s.center = balls[k].c;
    s.radius = balls[k].r;
    spheres.push_back(s);
    p.row(k) = balls[k].c.transpose();
    r[k] = balls[k].r;
    rows.push_back(static_cast<Index>(k));
  }
  const Ball want = brute_force(balls);
  ASSERT_TRUE(std::isfinite(want.r)) << what;
  for (const bvh::Sphere& got : {min_sphere_of_spheres(spheres), min_sphere_of_balls(p, r, rows.data(), rows.size())}) {
    for (const bvh::Sphere& s : spheres) EXPECT_TRUE(got.contains(s)) << what;
    const double tol = 1e-9 * (1.0 + want.r);
    EXPECT_NEAR(got.radius, want.r, tol) << what;
    // The minimal enclosing ball is unique, so the centres agree too (up to conditioning).
    EXPECT_LT((got.center - want.c).norm(), 1e-6 * (1.0 + want.r)) << what;
  }
}

TEST(Miniball, FewPointsDuplicatesCoplanarCollinear) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto rnd = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + trial % 4;
    std::vector<Ball> b;
    for (int i = 0; i < n; ++i) b.push_back({rnd(), 0.0});
    expect_matches(b, "1-4 points");
  }
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 a = rnd();
    expect_matches({{a, 0}, {a, 0}, {a, 0}}, "one point three times");
    const Vec3 c = rnd();
    expect_matches({{a, 0}, {c, 0}, {a, 0}, {c, 0}, {a, 0}}, "two points repeated");
    std::vector<Ball> plane, line;
    for (int i = 0; i < 7; ++i) {
      plane.push_back({Vec3(u(rng), u(rng), 0.3), 0.0});
      line.push_back({a + u(rng) * (c - a), 0.0});
    }
    expect_matches(plane, "coplanar points");
    expect_matches(line, "collinear points");
    // Four cocircular points (square corners) plus the centre.
    expect_matches({{Vec3(1, 0, 0), 0}, {Vec3(0, 1, 0), 0}, {Vec3(-1, 0, 0), 0}, {Vec3(0, -1, 0), 0}, {Vec3::Zero(), 0}},
                   "cocircular");
  }
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<Ball> b;
    for (int i = 0; i < 8; ++i) b.push_back({rnd(), 0.0});
    expect_matches(b, "8 random points");
  }
}

TEST(Miniball, SpheresOfDifferentRadii) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), ur(0.0, 0.8);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + trial % 7;
    std::vector<Ball> b;
    for (int i = 0; i < n; ++i) b.push_back({Vec3(u(rng), u(rng), u(rng)), ur(rng)});
    if (trial % 5 == 0) b.push_back({b[0].c, b[0].r * 0.5});  // one inside another (same centre)
    if (trial % 7 == 0) b.push_back(b[0]);                    // a duplicate
    expect_matches(b, "random spheres");
  }
}

TEST(Miniball, TwoSpheresClosedForm) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0), ur(0.0, 0.8);
  for (int trial = 0; trial < 500; ++trial) {
    bvh::Sphere a, b;
    a.center = Vec3(u(rng), u(rng), u(rng));
    b.center = trial % 10 == 0 ? a.center : Vec3(u(rng), u(rng), u(rng));
    a.radius = ur(rng);
    b.radius = ur(rng);
    const bvh::Sphere got = min_sphere_of_two(a, b);
    EXPECT_TRUE(got.contains(a) && got.contains(b));
    const bvh::Sphere cg = min_sphere_of_spheres({a, b});
    EXPECT_NEAR(got.radius, cg.radius, 1e-9);
  }
}

TEST(Miniball, LargeSetContainsAllAndIsNoLargerThanTheCentroidSphere) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  Points p(5000, 3);
  for (Index r = 0; r < 5000; ++r) p.row(r) = Vec3(g(rng), 2 * g(rng), 0.1 * g(rng)).transpose() + Vec3(1e3, -2e3, 5).transpose();
  Values radii = Values::Constant(5000, 0.01);
  IndexList rows(5000);
  for (Index r = 0; r < 5000; ++r) rows[r] = r;
  const bvh::Sphere s = min_sphere_of_balls(p, radii, rows.data(), rows.size());
  const bvh::Sphere fit = bvh::Sphere::fit(p, radii, rows.data(), rows.size());
  for (Index r = 0; r < 5000; ++r) EXPECT_TRUE(s.contains(p.row(r).transpose(), radii[r]));
  EXPECT_LE(s.radius, fit.radius);
  EXPECT_TRUE(min_sphere_of_points(p, {}).empty());
}

}  // namespace
}  // namespace surfeledit
