// The blend tool in a session (thesis §12.3, issue 10 §2, §5): a capsule merged into a sphere, then blended;
// truth from the exact signed distances of the two solids, not from the code.
#include <gtest/gtest.h>

#include <cmath>

#include "../expect_error.hpp"
#include "../session_fixture.hpp"
#include "blend_scenes.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

using test::CapsuleIntoSphere;

// Largest angle (radians) between the normals of two surfels closer than `reach` whose positions are both
// within `band` of the crease circle (brute force over the pairs).
double largest_crease_angle(const SurfelModel& m, double band, double reach) {
  IndexList rows;
  for (Index r = 0; r < m.size(); ++r)
    if (CapsuleIntoSphere::to_crease(m.positions().row(r).transpose()) < band) rows.push_back(r);
  double worst = 0.0;
  for (Index a : rows)
    for (Index b : rows) {
      if (b <= a || (m.positions().row(a) - m.positions().row(b)).norm() > reach) continue;
      const double c = std::clamp(m.normals().row(a).dot(m.normals().row(b)), -1.0, 1.0);
      worst = std::max(worst, std::acos(c));
    }
  return worst;
}

double deepest(const CapsuleIntoSphere& s, const IdList& ids) {
  double d = 0.0;
  for (SurfelId id : ids) d = std::min(d, s.sdf_union(s.session.model().positions().row(s.session.model().row_of(id)).transpose()));
  return d;
}

TEST(Blend, SmoothsTheCreaseInsideItsBandWithoutGaps) {
  CapsuleIntoSphere s;
  ASSERT_FALSE(s.merged.features.empty());
  const double h = s.spacing;
  const double before = largest_crease_angle(s.session.model(), 6 * h, 1.5 * h);
  BlendParams p;
  p.only_grow = true;
  const BlendOutcome b = s.session.blend(p);
  const SurfelModel& m = s.session.model();
  ASSERT_GT(b.particles, 100);
  EXPECT_EQ(b.moved.size(), static_cast<std::size_t>(b.particles));
  ASSERT_EQ(b.energy.size(), 50u);
  EXPECT_LT(b.energy.back(), 0.8 * b.energy.front());
  // The crease: measured 1.19 -> 0.29 rad (only_grow, 50 iterations).
  const double after = largest_crease_angle(m, 6 * h, 1.5 * h);
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, 0.5 * before);
  // Every particle stays in the blend band (range 4 mean radii around the features, which lie within about
  // a spacing of the crease circle), and none goes inside the union by more than a quarter spacing.
  for (SurfelId id : b.moved)
    EXPECT_LT(CapsuleIntoSphere::to_crease(m.positions().row(m.row_of(id)).transpose()), 4 * h + 2 * h);
  EXPECT_GE(deepest(s, b.moved), -0.25 * h);
  // No gap: every point of the union's surface within 3 spacings of the crease has a surfel within 1.5
  // spacings (points from fresh samples of both solids at half the spacing).
  KdTree tree(m.positions());
  int checked = 0;
  for (const Solid* solid : {s.sphere.get(), s.capsule.get()}) {
    const SampledSurfels fine = test::sample_solid(*solid, 0.5 * h, 7);
    for (Eigen::Index k = 0; k < fine.positions.rows(); ++k) {
      const Vec3 q = fine.positions.row(k).transpose();
      if (CapsuleIntoSphere::to_crease(q) > 3 * h || s.sdf_union(q) < -1e-9) continue;
      double d2 = 0.0;
      tree.nearest(q, &d2);
      EXPECT_LT(std::sqrt(d2), 1.5 * h) << "uncovered at " << q.transpose();
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(Blend, DefaultMovesBothWaysButStaysNearTheSurface) {
  CapsuleIntoSphere s;
  const double h = s.spacing;
  const double before = largest_crease_angle(s.session.model(), 6 * h, 1.5 * h);
  const BlendOutcome b = s.session.blend(BlendParams{});
  EXPECT_LT(largest_crease_angle(s.session.model(), 6 * h, 1.5 * h), 0.5 * before);
  // Without only_grow the particles also sink: measured 0.6 spacing at most.
  EXPECT_GE(deepest(s, b.moved), -1.0 * h);
  EXPECT_FALSE(s.session.model().has_clips() &&
               s.session.model().clip_dirs().row(s.session.model().row_of(b.moved.front())).norm() > 0);
}

TEST(Blend, OneHistoryEntryUndoneAndRedoneExactly) {
  CapsuleIntoSphere s;
  const Snapshot before(s.session);
  const std::uint64_t v = s.session.version();
  BlendParams p;
  p.iterations = 10;
  p.adaptive = true;
  const BlendOutcome b = s.session.blend(p, std::nullopt);  // the tool that merged blends (its features)
  EXPECT_EQ(s.session.version(), v + 1);
  EXPECT_EQ(s.session.history().back().op, "blend");
  EXPECT_EQ(s.session.history().back().author, "");
  for (SurfelId id : b.inserted) EXPECT_GE(s.session.model().row_of(id), 0);
  for (SurfelId id : b.removed) EXPECT_LT(s.session.model().row_of(id), 0);
  EXPECT_FALSE(b.removed.empty());  // the crease's gap-covering copies at least
  const Snapshot after(s.session);
  s.session.undo();
  expect_same(Snapshot(s.session), before, "undo");
  s.session.redo();
  expect_same(Snapshot(s.session), after, "redo");
}

TEST(Blend, CallingAgainContinues) {
  CapsuleIntoSphere s;
  BlendParams p;
  p.iterations = 20;
  const BlendOutcome first = s.session.blend(p);
  const BlendOutcome second = s.session.blend(p);
  EXPECT_TRUE(second.removed.empty());  // the crease's copies went with the first call
  EXPECT_LT(second.energy.front(), first.energy.front());
  EXPECT_EQ(s.session.history().size(), 5u + CapsuleIntoSphere::kSteps);  // load, regions, steps, merge, 2 blends
}

TEST(Blend, SameResultOnOneAndTwoThreads) {
  CapsuleIntoSphere one(0.02, 1), two(0.02, 2);
  BlendParams p;
  p.iterations = 5;
  one.session.blend(p);
  two.session.blend(p);
  EXPECT_TRUE(one.session.model().positions() == two.session.model().positions());
  EXPECT_TRUE(one.session.model().normals() == two.session.model().normals());
}

TEST(Blend, BadArgumentsAreTypedAndChangeNothing) {
  CapsuleIntoSphere s;
  const Snapshot before(s.session);
  const std::uint64_t v = s.session.version();
  BlendParams bad;
  bad.iterations = -1;
  testing_util::expect_error([&] { s.session.blend(bad); }, ErrorCode::InvalidArgument, "iterations");
  bad = BlendParams{};
  bad.dt = std::nan("");
  testing_util::expect_error([&] { s.session.blend(bad); }, ErrorCode::InvalidArgument, "dt");
  bad = BlendParams{};
  bad.range_factor = 0.0;
  testing_util::expect_error([&] { s.session.blend(bad); }, ErrorCode::InvalidArgument, "range_factor");
  testing_util::expect_error([&] { s.session.blend({}, IdList{999999}); }, ErrorCode::NotFound, "features");
  testing_util::expect_error([&] { s.session.blend({}, IdList{}); }, ErrorCode::InvalidArgument, "features");
  EXPECT_EQ(s.session.version(), v);
  expect_same(Snapshot(s.session), before, "refused");
  EditSession fresh("fresh");
  fresh.load(s.session.model());
  testing_util::expect_error([&] { fresh.blend({}); }, ErrorCode::Conflict, "features");  // no merge yet
}

}  // namespace
}  // namespace surfeledit
