// Hole filling (thesis §12.4.2, issue 10 §4, §5): a sphere and a torus with holes cut out, filled and checked
// against their exact signed distances; a half sphere's open rim is left alone; the session op's history entry
// and typed errors.
#include <gtest/gtest.h>


#include "expect_error.hpp"
#include "particles/blend_scenes.hpp"
#include "session_fixture.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

// Samples of `solid` with every sample within `hole_radius` of `centre` cut out (returned in `removed`).
SurfelArrays with_hole(const Solid& solid, double spacing, const Vec3& centre, double hole_radius, Points& removed) {
  const SampledSurfels s = test::sample_solid(solid, spacing, 3);
  std::vector<bool> keep(static_cast<std::size_t>(s.positions.rows()));
  Eigen::Index cut = 0;
  for (Eigen::Index k = 0; k < s.positions.rows(); ++k) {
    keep[k] = (s.positions.row(k).transpose() - centre).norm() > hole_radius;
    cut += !keep[k];
  }
  SurfelArrays a;
  a.positions.resize(s.positions.rows() - cut, 3);
  a.normals.resize(a.positions.rows(), 3);
  a.radii.resize(a.positions.rows());
  removed.resize(cut, 3);
  Eigen::Index j = 0, c = 0;
  for (Eigen::Index k = 0; k < s.positions.rows(); ++k) {
    if (!keep[k]) {
      removed.row(c++) = s.positions.row(k);
      continue;
    }
    a.positions.row(j) = s.positions.row(k);
    a.normals.row(j) = s.normals.row(k);
    a.radii[j++] = s.radii[k];
  }
  return a;
}

// Gradient of the sdf by central differences (the true normal at a surface point).
Vec3 sdf_normal(const Solid& s, const Vec3& p) {
  const double e = 1e-6;
  Vec3 g;
  for (int k = 0; k < 3; ++k) {
    Vec3 d = Vec3::Zero();
    d[k] = e;
    g[k] = (s.sdf(p + d) - s.sdf(p - d)) / (2 * e);
  }
  return g.normalized();
}

void check_fill(const Solid& solid, double spacing, const Vec3& centre, double hole_radius) {
  Points removed;
  EditSession session("holes");
  session.load(SurfelModel::from_arrays(with_hole(solid, spacing, centre, hole_radius, removed)));
  HoleParams p;
  p.max_diameter = 4.0 * hole_radius;
  const FillOutcome out = session.fill_holes(p);
  ASSERT_EQ(out.holes.size(), 1u);
  EXPECT_NEAR(out.holes[0].diameter, 2.0 * hole_radius, 0.25 * hole_radius);
  ASSERT_FALSE(out.inserted.empty());
  const SurfelModel& m = session.model();
  int aligned = 0;
  for (SurfelId id : out.inserted) {
    const Index r = m.row_of(id);
    const Vec3 x = m.positions().row(r).transpose(), n = m.normals().row(r).transpose();
    EXPECT_LT(std::abs(solid.sdf(x)), 0.1 * hole_radius) << x.transpose();
    EXPECT_LT((x - centre).norm(), hole_radius + 1.5 * spacing);  // inside the hole
    aligned += n.dot(sdf_normal(solid, x)) >= 0.9;
  }
  EXPECT_GE(aligned, 0.95 * out.inserted.size());
  KdTree tree(m.positions());
  int covered = 0;
  for (Eigen::Index k = 0; k < removed.rows(); ++k) {
    double d2 = 0.0;
    tree.nearest(removed.row(k).transpose(), &d2);
    covered += std::sqrt(d2) <= 1.5 * spacing;
  }
  EXPECT_GE(covered, 0.95 * removed.rows());
  EXPECT_GT(removed.rows(), 50);
}

TEST(Holes, SphereHoleFilledOnTheSphere) {
  const auto sphere = make_sphere(0.5);
  check_fill(*sphere, 0.02, Vec3(0, 0.3, 0.4), 0.15);
}

TEST(Holes, TorusHoleFilledOnTheTorus) {
  const auto torus = make_torus(0.5, 0.2);
  check_fill(*torus, 0.015, Vec3(0.7, 0, 0), 0.1);
}

TEST(Holes, HalfSphereRimIsNotFilled) {
  const auto sphere = make_sphere(0.5);
  Points removed;
  // The lower half cut away: the rim (diameter 1) is the scan's border.
  SurfelArrays half = with_hole(*sphere, 0.02, Vec3(0, 0, -0.5), 0.5 * std::sqrt(2.0), removed);
  EditSession session("half");
  session.load(SurfelModel::from_arrays(half));
  const std::uint64_t v = session.version();
  HoleParams p;
  p.max_diameter = 0.5;
  const FillOutcome out = session.fill_holes(p);
  EXPECT_TRUE(out.holes.empty());
  EXPECT_TRUE(out.inserted.empty());
  EXPECT_GE(out.skipped, 1);
  EXPECT_EQ(session.version(), v);  // nothing changed, no history entry
}

TEST(Holes, ClosedSurfaceHasNoBoundary) {
  const auto sphere = make_sphere(0.5);
  const SurfelModel m = SurfelModel::from_arrays(test::arrays_of(test::sample_solid(*sphere, 0.02)));
  HoleParams p;
  p.max_diameter = 1.0;
  EXPECT_TRUE(group_loops(m, boundary_rows(m, p), p).empty());
}

TEST(Holes, OneHistoryEntryAndTypedErrors) {
  const auto sphere = make_sphere(0.5);
  Points removed;
  EditSession session("holes");
  session.load(SurfelModel::from_arrays(with_hole(*sphere, 0.02, Vec3(0, 0, 0.5), 0.12, removed)));
  const Snapshot before(session);
  const std::uint64_t v = session.version();
  HoleParams bad;
  testing_util::expect_error([&] { session.fill_holes(bad); }, ErrorCode::InvalidArgument, "max_diameter");  // 0
  bad.max_diameter = 1.0;
  bad.iterations = -2;
  testing_util::expect_error([&] { session.fill_holes(bad); }, ErrorCode::InvalidArgument, "iterations");
  HoleParams p;
  p.max_diameter = 1.0;
  testing_util::expect_error([&] { session.fill_holes(p, IdList{12345678}); }, ErrorCode::NotFound, "boundary");
  testing_util::expect_error([&] { session.fill_holes(p, IdList{}); }, ErrorCode::InvalidArgument, "boundary");
  EXPECT_EQ(session.version(), v);
  expect_same(Snapshot(session), before, "refused");
  const FillOutcome out = session.fill_holes(p, std::nullopt, "fay");
  ASSERT_FALSE(out.inserted.empty());
  EXPECT_EQ(session.history().back().op, "fill_holes");
  // The override: the same boundary given explicitly fills the same way.
  const IdList boundary = out.holes[0].boundary;
  const Snapshot filled(session);
  session.undo();
  expect_same(Snapshot(session), before, "undo");
  const FillOutcome again = session.fill_holes(p, boundary);
  EXPECT_EQ(again.inserted.size(), out.inserted.size());
}

}  // namespace
}  // namespace surfeledit
