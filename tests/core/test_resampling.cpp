// Dynamic resampling: tangent frames, split plans (geometry checked by hand), the session splitting
// stretched surfels with new stable ids while detection keeps running.
#include <gtest/gtest.h>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/resampling.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {

TEST(Resampling, TangentFramesAreOrthogonalAndScaled) {
  Points n(3, 3);
  n << 0, 0, 1, 1, 0, 0, 0.6, 0.8, 0;
  Values r(3);
  r << 1.0, 2.0, 0.5;
  Points u, v;
  make_tangent_frames(n, r, u, v);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(u.row(i).norm(), r[i], 1e-12);
    EXPECT_NEAR(v.row(i).norm(), r[i], 1e-12);
    EXPECT_NEAR(u.row(i).dot(v.row(i)), 0.0, 1e-12);
    EXPECT_NEAR(u.row(i).dot(n.row(i)), 0.0, 1e-12);
    EXPECT_NEAR(v.row(i).dot(n.row(i)), 0.0, 1e-12);
  }
}

TEST(Resampling, SplitsAlongTheGreatestStretch) {
  SurfelArrays a;
  a.positions.setZero(2, 3);
  a.positions(1, 0) = 5.0;
  a.normals.resize(2, 3);
  a.normals << 0, 0, 1, 0, 0, 1;
  a.radii.setConstant(2, 1.0);
  a.tangent_u.resize(2, 3);
  a.tangent_v.resize(2, 3);
  // Row 0 stretched to 3 along (1, 1, 0)/sqrt2, 1 across; row 1 unstretched.
  const Vec3 e = Vec3(1, 1, 0).normalized(), f = Vec3(-1, 1, 0).normalized();
  a.tangent_u.row(0) = (3.0 * e).transpose();
  a.tangent_v.row(0) = f.transpose();
  a.tangent_u.row(1) << 1, 0, 0;
  a.tangent_v.row(1) << 0, 1, 0;
  const Values rest = Values::Ones(2);
  const SplitPlan plan = plan_splits(a, {0, 1}, rest, ResampleParams{true, 1.5});
  ASSERT_EQ(plan.parents, IndexList{0});
  const Vec3 pa = plan.a.positions.row(0).transpose(), pb = plan.b.positions.row(0).transpose();
  EXPECT_NEAR((pa - (-1.5 * e)).norm(), 0.0, 1e-12);  // p -/+ (a_e / 2) e
  EXPECT_NEAR((pb - (1.5 * e)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(plan.a.tangent_u.row(0).dot(e)), 1.5, 1e-12);  // halved along e
  EXPECT_NEAR(plan.a.tangent_v.row(0).norm(), 1.0, 1e-12);           // kept across
  EXPECT_NEAR(plan.a.radii[0], 1.5, 1e-12);
  EXPECT_EQ(plan.b.normals.row(0), a.normals.row(0));
  // Not stretched beyond 3 x rest: no split.
  EXPECT_TRUE(plan_splits(a, {0, 1}, rest, ResampleParams{true, 3.5}).parents.empty());
  EXPECT_THROW(plan_splits(a, {1, 0}, rest, ResampleParams{true, 1.5}), Error);  // not ascending
  EXPECT_THROW(validate(ResampleParams{true, 0.9}), Error);
}

// A plank whose right end is pulled away: the blend region stretches and splits.
struct Pulled {
  EditSession session{"r"};
  IdList zero, one;
  Pulled() {
    auto plank = make_box(Vec3(1.0, 0.3, 0.1));
    const SampledSurfels s = plank->sample(SampleParams{0.05, 1, 0.25});
    SurfelArrays a;
    a.positions = s.positions;
    a.normals = s.normals;
    a.radii = s.radii;
    session.load(SurfelModel::from_arrays(a));
    for (Index r = 0; r < s.positions.rows(); ++r) {
      if (s.positions(r, 0) < -0.2) zero.push_back(static_cast<SurfelId>(r));
      if (s.positions(r, 0) > 0.2) one.push_back(static_cast<SurfelId>(r));
    }
    session.set_regions({zero, {}}, {one, {}});
  }
};

TEST(Resampling, SessionSplitsWithStableIds) {
  Pulled f;
  f.session.configure({{"resample", true}, {"split_threshold", 1.3}});
  const IdList ids_before = f.session.model().ids();
  const Points before = f.session.model().positions();
  DeformParams p;
  p.translation = Vec3(0.4, 0, 0);
  p.blend = Blend::Linear;
  std::size_t inserted = 0;
  for (int k = 0; k < 3; ++k) {
    const std::uint64_t next = f.session.model().next_id();
    const std::uint64_t v = f.session.version();
    const StepResult o = f.session.deform(p);
    inserted += o.inserted.size();
    for (SurfelId id : o.inserted) {
      EXPECT_GE(id, next);                       // fresh ids
      EXPECT_GE(f.session.model().row_of(id), 0);
    }
    EXPECT_TRUE(o.detected);
    EXPECT_EQ(o.stats.deformable, static_cast<Index>(f.session.fields()->deformable.size()));
    const Changes c = f.session.changes_since(v);
    for (SurfelId id : o.inserted) EXPECT_TRUE(std::binary_search(c.changed.begin(), c.changed.end(), id));
    EXPECT_EQ(f.session.fields()->regions.size(), static_cast<std::size_t>(f.session.model().size()));
  }
  EXPECT_GT(inserted, 0u);
  EXPECT_TRUE(f.session.model().has_tangents());
  // Original ids still present; zero surfels untouched.
  for (SurfelId id : ids_before) EXPECT_GE(f.session.model().row_of(id), 0);
  for (SurfelId id : f.zero) {
    const Index r = f.session.model().row_of(id);
    EXPECT_EQ(f.session.model().positions().row(r), before.row(static_cast<Index>(id)));
  }
  // Pulling apart collides with nothing.
  EXPECT_TRUE(f.session.colliding().empty());
  bool listed = false;
  for (const auto& s : f.session.report().structures) listed |= s.name == "resampling";
  EXPECT_TRUE(listed);
}

}  // namespace
}  // namespace surfeledit
