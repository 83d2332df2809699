// Boolean operations of two models (thesis §12.4.1, issue 10 §3, §5): kept / dropped surfels against the exact
// signed distances of two analytic solids (sphere and box, torus and cylinder), difference normals, feature
// surfels, the session op with its history entry and typed errors.
#include <gtest/gtest.h>


#include "expect_error.hpp"
#include "particles/blend_scenes.hpp"
#include "session_fixture.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

struct Pair {
  std::unique_ptr<Solid> a, b;
  double spacing;
};

Pair sphere_and_box() {
  Pose p;
  p.translation = Vec3(0.35, 0.2, 0.1);
  p.rotation = Eigen::AngleAxisd(0.5, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  return {make_sphere(0.5), make_box(Vec3(0.4, 0.3, 0.35), p), 0.03};
}

Pair torus_and_cylinder() {
  Pose p;
  p.translation = Vec3(0.5, 0.0, 0.0);
  p.rotation = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
  return {make_torus(0.5, 0.18), make_cylinder(0.12, 0.5, p), 0.02};
}

struct Counts {
  std::size_t tp = 0, fp = 0, fn = 0;
  double precision() const { return tp + fp == 0 ? 1.0 : double(tp) / double(tp + fp); }
  double recall() const { return tp + fn == 0 ? 1.0 : double(tp) / double(tp + fn); }
};

// True when `x` (one of the op's inputs) belongs in the result, from the other solid's sdf.
bool belongs(BooleanOp op, bool of_a, double sdf_other) {
  const bool inside = sdf_other < 0.0;
  if (op == BooleanOp::Union) return !inside;
  if (op == BooleanOp::Intersection) return inside;
  return of_a ? !inside : inside;
}

double sdf_result(BooleanOp op, const Pair& s, const Vec3& p) {
  const double a = s.a->sdf(p), b = s.b->sdf(p);
  if (op == BooleanOp::Union) return std::min(a, b);
  if (op == BooleanOp::Intersection) return std::max(a, b);
  return std::max(a, -b);
}

void check_op(const Pair& s, BooleanOp op) {
  SCOPED_TRACE(enum_name(op));
  const SampledSurfels sa = test::sample_solid(*s.a, s.spacing, 1), sb = test::sample_solid(*s.b, s.spacing, 2);
  EditSession session("bool");
  session.load(SurfelModel::from_arrays(test::arrays_of(sa)));
  const MergeOutcome out = session.boolean(op, test::arrays_of(sb));
  const SurfelModel& m = session.model();
  EXPECT_EQ(out.inserted.size() + static_cast<std::size_t>(sa.positions.rows()) - out.removed.size(),
            static_cast<std::size_t>(m.size()));
  KdTree tree(m.positions());
  Counts counts;
  for (int side = 0; side < 2; ++side) {
    const SampledSurfels& in = side == 0 ? sa : sb;
    const Solid& other = side == 0 ? *s.b : *s.a;
    for (Eigen::Index k = 0; k < in.positions.rows(); ++k) {
      const Vec3 p = in.positions.row(k).transpose();
      const double d = other.sdf(p);
      if (std::abs(d) < s.spacing) continue;  // the band of one spacing
      double d2 = 0.0;
      tree.nearest(p, &d2);
      const bool kept = d2 == 0.0, truth = belongs(op, side == 0, d);
      counts.tp += kept && truth;
      counts.fp += kept && !truth;
      counts.fn += !kept && truth;
    }
  }
  EXPECT_GE(counts.precision(), 0.99);
  EXPECT_GE(counts.recall(), 0.99);
  EXPECT_GT(counts.tp, 500u);
  // Normals point out of the result (difference: B's flipped ones too): the result's sdf grows along them.
  std::size_t good = 0, total = 0;
  for (Index r = 0; r < m.size(); ++r) {
    const Vec3 p = m.positions().row(r).transpose(), n = m.normals().row(r).transpose();
    if (std::abs(s.a->sdf(p)) < s.spacing && std::abs(s.b->sdf(p)) < s.spacing) continue;
    const double e = 0.5 * s.spacing;
    good += sdf_result(op, s, p + e * n) > sdf_result(op, s, p - e * n);
    ++total;
  }
  EXPECT_GE(double(good), 0.99 * double(total));
  // Feature surfels lie near both surfaces (within two spacings of the other solid's surface).
  ASSERT_FALSE(out.features.empty());
  for (SurfelId id : out.features) {
    const Index r = m.row_of(id);
    ASSERT_GE(r, 0);
    const Vec3 p = m.positions().row(r).transpose();
    EXPECT_LT(std::min(std::abs(s.a->sdf(p)), std::abs(s.b->sdf(p))), 1e-9 + 0.01 * s.spacing);
    EXPECT_LT(std::max(std::abs(s.a->sdf(p)), std::abs(s.b->sdf(p))), 2.0 * s.spacing)
        << "id " << id << " of " << sa.positions.rows() << " a " << s.a->sdf(p) << " b " << s.b->sdf(p) << " n "
        << m.normals().row(r);
  }
}

TEST(Boolean, SphereAndBoxAgainstExactSdfs) {
  const Pair s = sphere_and_box();
  for (BooleanOp op : {BooleanOp::Union, BooleanOp::Intersection, BooleanOp::Difference}) check_op(s, op);
}

TEST(Boolean, TorusAndCylinderAgainstExactSdfs) {
  const Pair s = torus_and_cylinder();
  for (BooleanOp op : {BooleanOp::Union, BooleanOp::Intersection, BooleanOp::Difference}) check_op(s, op);
}

TEST(Boolean, OneHistoryEntryThenBlendThenUndoExactly) {
  const Pair s = sphere_and_box();
  const SampledSurfels sa = test::sample_solid(*s.a, s.spacing, 1), sb = test::sample_solid(*s.b, s.spacing, 2);
  EditSession session("bool");
  session.load(SurfelModel::from_arrays(test::arrays_of(sa)));
  const Snapshot before(session);
  const MergeOutcome out = session.boolean(BooleanOp::Difference, test::arrays_of(sb), {}, "eve");
  EXPECT_EQ(session.history().back().op, "boolean");
  EXPECT_EQ(session.history().back().author, "eve");
  EXPECT_TRUE(out.moved.empty());
  const Snapshot after(session);
  BlendParams p;
  p.iterations = 10;
  const BlendOutcome b = session.blend(p, std::nullopt, "eve");  // follows eve's boolean's features (open region: spring)
  EXPECT_GT(b.particles, 0);
  session.undo();
  expect_same(Snapshot(session), after, "undo blend");
  session.undo();
  expect_same(Snapshot(session), before, "undo boolean");
}

TEST(Boolean, BadArgumentsAreTypedAndChangeNothing) {
  const Pair s = sphere_and_box();
  const SampledSurfels sa = test::sample_solid(*s.a, s.spacing, 1), sb = test::sample_solid(*s.b, s.spacing, 2);
  EditSession session("bool");
  session.load(SurfelModel::from_arrays(test::arrays_of(sa)));
  const Snapshot before(session);
  const std::uint64_t v = session.version();
  SurfelArrays bad = test::arrays_of(sb);
  bad.normals.row(3).setZero();
  testing_util::expect_error([&] { session.boolean(BooleanOp::Union, bad); }, ErrorCode::InvalidArgument, "normals");
  bad = test::arrays_of(sb);
  bad.positions(5, 1) = std::nan("");
  testing_util::expect_error([&] { session.boolean(BooleanOp::Union, bad); }, ErrorCode::InvalidArgument, "positions");
  bad = test::arrays_of(sb);
  bad.radii.conservativeResize(3);
  testing_util::expect_error([&] { session.boolean(BooleanOp::Union, bad); }, ErrorCode::InvalidArgument, "radii");
  BooleanParams bp;
  bp.feature_factor = -1;
  testing_util::expect_error([&] { session.boolean(BooleanOp::Union, test::arrays_of(sb), bp); }, ErrorCode::InvalidArgument,
                             "feature_factor");
  // Disjoint solids: their intersection is empty.
  SampledSurfels far = sb;
  far.positions.col(0).array() += 10.0;
  testing_util::expect_error([&] { session.boolean(BooleanOp::Intersection, test::arrays_of(far)); }, ErrorCode::Conflict, "op");
  EXPECT_EQ(session.version(), v);
  expect_same(Snapshot(session), before, "refused");
}

}  // namespace
}  // namespace surfeledit
