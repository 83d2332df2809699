// Step validation (deformation.hpp: kMaxStepAngle, kStepReach, the axis's normalised length) and the
// all-or-nothing deform of EditSession: a refused or failed step changes nothing, version included.
#include <gtest/gtest.h>

#include <cmath>

#include "expect_error.hpp"
#include "session_fixture.hpp"
#include "surfeledit/core/deformation.hpp"

namespace surfeledit {
namespace {

DeformParams rotation(const Vec3& axis, double angle) {
  DeformParams p;
  p.axis = axis;
  p.angle = angle;
  return p;
}

TEST(StepBounds, AxisMustNormaliseToUnitLength) {
  // (1e200, 1e200, 0): its norm overflows, axis / norm is zero and the rotation would collapse F1.
  EXPECT_FALSE(std::isfinite(Vec3(1e200, 1e200, 0).norm()));
  testing_util::expect_error([] { validate(rotation({1e200, 1e200, 0}, M_PI / 2)); }, ErrorCode::InvalidArgument,
                             "axis");
  testing_util::expect_error([] { validate(rotation({1e-170, 1e-170, 0}, 1.0)); }, ErrorCode::InvalidArgument,
                             "axis");  // the squared norm underflows to zero
  testing_util::expect_error([] { validate(rotation({0, 0, 0}, 1.0)); }, ErrorCode::InvalidArgument, "axis");
  validate(rotation({0, 0, 0}, 0.0));  // no rotation: the axis is unused
  validate(rotation({1e100, 1e100, 0}, 1.0));
  validate(rotation({1e-100, 0, 1e-100}, 1.0));
  // Independent truth: the axis apply_step uses has unit length whenever validate() accepts.
  for (const Vec3& a : {Vec3(1e100, 1e100, 0), Vec3(3, 4, 0), Vec3(1e-100, 0, 1e-100)})
    EXPECT_NEAR(a.normalized().norm(), 1.0, 1e-12);
}

TEST(StepBounds, AngleTranslationAndCentreAgainstTheModel) {
  testing_util::expect_error([] { validate(rotation({0, 0, 1}, kMaxStepAngle * 1.01)); }, ErrorCode::InvalidArgument,
                             "angle");
  validate(rotation({0, 0, 1}, -kMaxStepAngle));
  DeformationFields f;
  f.box_centre = Vec3(10, 0, 0);
  f.box_extent = 2.0;
  DeformParams p;
  p.translation = Vec3(0, kStepReach * 2.0 * 0.999, 0);
  validate(p, f);
  p.translation = Vec3(0, kStepReach * 2.0 * 1.001, 0);
  testing_util::expect_error([&] { validate(p, f); }, ErrorCode::InvalidArgument, "translation");
  p.translation = Vec3(1e308, 0, 0);
  testing_util::expect_error([&] { validate(p, f); }, ErrorCode::InvalidArgument, "translation");
  p = rotation({0, 0, 1}, 0.1);
  p.center = Vec3(10 + kStepReach * 2.0 * 1.001, 0, 0);
  testing_util::expect_error([&] { validate(p, f); }, ErrorCode::InvalidArgument, "center");
  p.center = Vec3(10 - kStepReach * 2.0 * 0.999, 0, 0);
  validate(p, f);
  f.box_extent = std::numeric_limits<double>::infinity();  // unknown extent: no reach check
  p.center = Vec3(1e300, 0, 0);
  validate(p, f);
}

TEST(StepBounds, FieldsRecordTheBoundingBoxOfThePositions) {
  SessionFixture fx;
  std::vector<Region> regions(static_cast<std::size_t>(fx.s.positions.rows()), Region::Zero);
  for (Index i : fx.one) regions[static_cast<std::size_t>(i)] = Region::One;
  const DeformationFields f = compute_fields(fx.s.positions, regions, 1);
  Vec3 lo = fx.s.positions.row(0).transpose(), hi = lo;
  for (Eigen::Index i = 0; i < fx.s.positions.rows(); ++i) {
    lo = lo.cwiseMin(fx.s.positions.row(i).transpose());
    hi = hi.cwiseMax(fx.s.positions.row(i).transpose());
  }
  EXPECT_NEAR(f.box_extent, (hi - lo).norm(), 1e-12);
  EXPECT_LT((f.box_centre - 0.5 * (lo + hi)).norm(), 1e-12);
}

// The probe: deform(translation=(1e308, 0, 0)) twice. Both are refused; nothing moves, not even
// the version, and the session keeps working.
TEST(StepBounds, AHugeStepIsRefusedTwiceAndChangesNothing) {
  SessionFixture fx;
  fx.session.set_regions({fx.zero, {}}, {fx.one, {}});
  DeformParams small;
  small.translation = Vec3(0, 0, -0.01);
  fx.session.deform(small);
  const Snapshot before(fx.session);
  const std::uint64_t version = fx.session.version();
  DeformParams huge;
  huge.translation = Vec3(1e308, 0, 0);
  for (int i = 0; i < 2; ++i) {
    testing_util::expect_error([&] { fx.session.deform(huge); }, ErrorCode::InvalidArgument, "translation");
    expect_same(before, Snapshot(fx.session), "after a refused step");
    EXPECT_EQ(fx.session.version(), version);
  }
  testing_util::expect_error([&] { fx.session.deform(rotation({1e200, 1e200, 0}, M_PI / 2)); },
                             ErrorCode::InvalidArgument, "axis");
  expect_same(before, Snapshot(fx.session), "after a collapsing axis");
  fx.session.deform(small);
  EXPECT_EQ(fx.session.version(), version + 1);
}

// A step that fails after apply_step wrote the rows is rolled back to the exact state before it. Response
// "merge" with the one region (the sphere's bottom cap) pushed wholly into the slab: the merge would
// remove every one-region surfel, so it throws Conflict after the step was applied. Before the roll-back
// the step stayed applied and the version moved on.
TEST(StepBounds, AStepThatFailsAfterApplyingIsRolledBack) {
  SessionFixture fx;
  IdList cap, rest;
  for (SurfelId id : fx.one) (fx.s.positions(static_cast<Eigen::Index>(id), 2) < 0.56 ? cap : rest).push_back(id);
  ASSERT_GT(cap.size(), 3u);
  fx.session.configure({{"response", std::string("merge")}});
  fx.session.set_regions({fx.zero, {}}, {cap, {}});
  const Snapshot before(fx.session);
  const std::uint64_t version = fx.session.version();
  const auto history = fx.session.history().size();
  DeformParams step;
  step.translation = Vec3(0, 0, -0.53);  // the cap (z in [0.5, 0.56]) lands inside the slab (|z| < 0.15)
  testing_util::expect_error([&] { fx.session.deform(step); }, ErrorCode::Conflict, "merge");
  expect_same(before, Snapshot(fx.session), "after the failed step");
  EXPECT_EQ(fx.session.version(), version);
  EXPECT_EQ(fx.session.history().size(), history);
  EXPECT_TRUE(fx.session.changes_since(version).changed.empty());
  step.translation = Vec3(0, 0, -0.01);
  fx.session.deform(step);  // the session is not poisoned
  EXPECT_EQ(fx.session.version(), version + 1);
}

// Coordinates whose squared distances overflow break nearest-neighbour search: regions are refused.
TEST(StepBounds, RegionsNeedCoordinatesWithinTheSearchableRange) {
  SessionFixture fx;
  SurfelArrays a;
  a.positions = fx.s.positions * 1e200;
  a.normals = fx.s.normals;
  a.radii = fx.s.radii * 1e200;
  EditSession session("big");
  session.load(SurfelModel::from_arrays(a));
  const std::uint64_t version = session.version();
  testing_util::expect_error([&] { session.set_regions({fx.zero, {}}, {fx.one, {}}); },
                             ErrorCode::InvalidArgument, "positions");
  EXPECT_EQ(session.version(), version);
}

}  // namespace
}  // namespace surfeledit
