// Sharp crease: the three-plane point against hand-solved planes, the gap copies of Eq. 11.1 against
// their formula; on the analytic scenes, the moved feature surfels lie within 0.1 spacing of both exact
// surfaces and each clip keeps the half outside the other solid.
#include <gtest/gtest.h>

#include <cstdio>

#include "response_scenes.hpp"
#include "surfeledit/core/response/crease.hpp"
#include "surfeledit/core/response/merge.hpp"

namespace surfeledit {
namespace {

using testing::ResponseScene;

TEST(Crease, ThreePlanePointOfTwoOrthogonalPlanes) {
  // Planes z = 0 and x = 0; the midpoint plane is y = 0.35.
  Vec3 x;
  ASSERT_TRUE(crease_point(Vec3(0.3, 0.2, 0), Vec3::UnitZ(), Vec3(0, 0.5, 0.4), Vec3::UnitX(), 0.1, x));
  EXPECT_NEAR((x - Vec3(0, 0.35, 0)).norm(), 0.0, 1e-15);
  // Far from the origin the same configuration gives the same point.
  const Vec3 far(1e6, -2e6, 3e6);
  ASSERT_TRUE(crease_point(far + Vec3(0.3, 0.2, 0), Vec3::UnitZ(), far + Vec3(0, 0.5, 0.4), Vec3::UnitX(), 0.1, x));
  EXPECT_NEAR((x - far - Vec3(0, 0.35, 0)).norm(), 0.0, 1e-9);
  // Parallel planes: no crease.
  EXPECT_FALSE(crease_point(Vec3::Zero(), Vec3::UnitZ(), Vec3(1, 0, 0.1), Vec3(0, 0.05, 1).normalized(), 0.1, x));
}

// Two surfels on the planes z = 0 and x = 0, radius 0.25.
SurfelModel corner(bool tangents) {
  SurfelArrays a;
  a.positions.resize(2, 3);
  a.positions << 0.3, 0.2, 0, 0, 0.5, 0.4;
  a.normals.resize(2, 3);
  a.normals << 0, 0, 1, 1, 0, 0;
  a.radii = Values::Constant(2, 0.25);
  if (tangents) {
    a.tangent_u.resize(2, 3);
    a.tangent_v.resize(2, 3);
    a.tangent_u << 0.25, 0, 0, 0, 0, 0.25;
    a.tangent_v << 0, 0.25, 0, 0, 0.25, 0;
  }
  return SurfelModel::from_arrays(a);
}

TEST(Crease, GapCopiesFollowEq11_1WithTangents) {
  const SurfelModel m = corner(true);
  CreaseParams p;
  p.max_move_factor = 2.0;
  const CreaseResult c = crease(m, {0}, {1}, p);
  ASSERT_EQ(c.moved, (IdList{0, 1}));
  for (int k = 0; k < 2; ++k) EXPECT_NEAR((c.positions.row(k) - Vec3(0, 0.35, 0).transpose()).norm(), 0.0, 1e-15);
  ASSERT_EQ(c.inserted_parents, (IdList{0, 1}));
  // Surfel 0 moved by (-0.3, 0.15, 0): along u (|d_u| = 0.3 > |d_v|); the copy spans x in [0, 0.55]
  // (from the old disc's far edge to the curve).
  EXPECT_NEAR((c.inserted.positions.row(0) - Vec3(0.275, 0.2, 0).transpose()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((c.inserted.tangent_u.row(0) - Vec3(0.275, 0, 0).transpose()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((c.inserted.tangent_v.row(0) - Vec3(0, 0.25, 0).transpose()).norm(), 0.0, 1e-15);
  // Surfel 1 moved by (0, -0.15, -0.4): along its u = z; the copy spans z in [0, 0.65].
  EXPECT_NEAR((c.inserted.positions.row(1) - Vec3(0, 0.5, 0.325).transpose()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((c.inserted.tangent_u.row(1) - Vec3(0, 0, 0.325).transpose()).norm(), 0.0, 1e-15);
  EXPECT_EQ(c.inserted.normals.row(1), Vec3::UnitX().transpose());
  // Clip lines run along the curve (the y axis); the kept half of surfel 0 is x >= 0, of 1 z >= 0.
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(std::abs(c.clip_dirs(k, 1)), 1.0, 1e-15);
  EXPECT_GT(Vec3(m.normals().row(0)).cross(Vec3(c.clip_dirs.row(0)))[0], 0.99);
  EXPECT_GT(Vec3(m.normals().row(1)).cross(Vec3(c.clip_dirs.row(1)))[2], 0.99);
}

TEST(Crease, GapCopiesOfCircularDiscs) {
  CreaseParams p;
  p.max_move_factor = 2.0;
  const CreaseResult c = crease(corner(false), {0}, {1}, p);
  ASSERT_EQ(c.inserted_parents.size(), 2u);
  // Surfel 0 moved by d = (-0.3, 0.15, 0), |d| = 0.335: centre p - (r - |d|)/2 d/|d|, radius (r + |d|)/2.
  const Vec3 d(-0.3, 0.15, 0);
  const double r = 0.25, dn = d.norm();
  EXPECT_NEAR((Vec3(c.inserted.positions.row(0)) - (Vec3(0.3, 0.2, 0) - 0.5 * (r - dn) * d / dn)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(c.inserted.radii[0], 0.5 * (r + dn), 1e-15);
  EXPECT_EQ(c.inserted.tangent_u.rows(), 0);
}

TEST(Crease, AppliedToTheModel) {
  SurfelModel m = corner(true);
  CreaseParams p;
  p.max_move_factor = 2.0;
  const CreaseResult c = crease(m, {0}, {1}, p);
  const IdList copies = apply_crease(m, c);
  ASSERT_EQ(copies, (IdList{2, 3}));
  EXPECT_EQ(Vec3(m.positions().row(0)), Vec3(c.positions.row(0)));
  EXPECT_EQ(Vec3(m.clip_dirs().row(1)), Vec3(c.clip_dirs.row(1)));
  EXPECT_EQ(Vec3(m.clip_dirs().row(m.row_of(2))), Vec3::Zero());  // copies are unclipped
  EXPECT_EQ(Vec3(m.tangent_u().row(m.row_of(3))), Vec3(c.inserted.tangent_u.row(1)));
  EXPECT_EQ(m.size(), 4);
}

TEST(Crease, SmallMovesNeedNoCopy) {
  CreaseParams p;
  p.gap_factor = 10.0;
  EXPECT_TRUE(crease(corner(false), {0}, {1}, p).inserted_parents.empty());
  p = {};
  p.max_move_factor = 1.0;  // both would move more than one radius (0.335, 0.427 > 0.25): they stay
  EXPECT_TRUE(crease(corner(false), {0}, {1}, p).moved.empty());
}

void check_crease(const char* name, const ResponseScene& sc) {
  SCOPED_TRACE(name);
  const double s = sc.spacing;
  const MergeResult m = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, sc.colliding);
  const CreaseResult c = crease(sc.model, m.features_deformable, m.features_zero);
  const std::size_t features = m.features_deformable.size() + m.features_zero.size();
  EXPECT_GE(c.moved.size(), features * 9 / 10);
  const IndexList rows = sc.model.rows_of(c.moved, "moved");
  double worst = 0.0;
  std::size_t outside = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Index r = rows[k];
    const Vec3 x = c.positions.row(static_cast<Eigen::Index>(k)).transpose();
    const bool zero = sc.regions[r] == Region::Zero;
    worst = std::max({worst, std::abs(sc.sdf_zero(x)), std::abs(sc.sdf_deformed(x))});
    const Vec3 n = sc.model.normals().row(r).transpose(), dir = c.clip_dirs.row(static_cast<Eigen::Index>(k)).transpose();
    EXPECT_NEAR(dir.norm(), 1.0, 1e-12);
    EXPECT_NEAR(dir.dot(n), 0.0, 1e-12);
    const Vec3 kept = x + 0.5 * s * n.cross(dir);  // half a radius into the kept half
    outside += (zero ? sc.sdf_deformed(kept) : sc.sdf_zero(kept)) > 0.0;
  }
  EXPECT_LE(worst, 0.1 * s);
  EXPECT_GE(outside, rows.size() * 95 / 100);
  std::printf("[crease %s] features=%zu moved=%zu copies=%zu worst surface distance %.3f s, kept half outside %zu/%zu\n",
              name, features, c.moved.size(), c.inserted_parents.size(), worst / s, outside, rows.size());
}

TEST(Crease, MovedFeaturesLieOnBothExactSurfaces) {
  check_crease("sphere_into_box", testing::sphere_into_box());
  check_crease("arm_into_sphere", testing::arm_into_sphere());
  check_crease("ball_into_cup", testing::ball_into_cup());
  check_crease("two_contacts", testing::two_contacts());
}

// Merge, remove, crease, apply: the model keeps nothing deep inside the other solid, copies included.
TEST(Crease, EndToEndOnTheModel) {
  const ResponseScene sc = testing::two_contacts();
  const MergeResult m = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, sc.colliding);
  SurfelModel model = sc.model;
  model.remove(m.removed);
  const CreaseResult c = crease(model, m.features_deformable, m.features_zero);
  const IdList copies = apply_crease(model, c);
  ASSERT_EQ(model.size(), sc.model.size() - static_cast<Index>(m.removed.size()) + static_cast<Index>(copies.size()));
  ASSERT_TRUE(model.has_clips());
  for (Index r = 0; r < model.size(); ++r) {
    const Vec3 p = model.positions().row(r).transpose();
    // The side of a row: the deformable ids are those of the original model's deformable rows.
    const Index original_row = sc.model.row_of(model.id_of(r));
    const SurfelId parent = original_row >= 0 ? model.id_of(r)
                                              : c.inserted_parents[static_cast<std::size_t>(model.id_of(r) - copies.front())];
    const bool zero = sc.regions[static_cast<std::size_t>(sc.model.row_of(parent))] == Region::Zero;
    const double other = zero ? sc.sdf_deformed(p) : sc.sdf_zero(p);
    EXPECT_GE(other, -0.25 * sc.spacing) << "id " << model.id_of(r);
  }
}

TEST(Crease, NumericalExtremes) {
  for (const testing::Frame& f : testing::extreme_frames()) {
    SCOPED_TRACE("scale " + std::to_string(f.scale) + " offset " + std::to_string(f.offset.norm()));
    check_crease("sphere_into_box", testing::sphere_into_box(f));
    check_crease("arm_into_sphere", testing::arm_into_sphere(f));
  }
}

}  // namespace
}  // namespace surfeledit
