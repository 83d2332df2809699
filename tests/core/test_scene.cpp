// Analytic solids: samples on the surface, exact normals (= SDF gradient), counts, determinism.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <random>

#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {


Pose tilted_pose(const Vec3& t) {
  Pose p;
  p.rotation = Eigen::AngleAxisd(1.1, Vec3(-2, 1, 0.5).normalized()).toRotationMatrix();
  p.translation = t;
  return p;
}

struct SolidCase {
  std::string name;
  std::function<std::unique_ptr<Solid>()> make;
  double scale;          // characteristic size, model units
  double spacing;        // sampling spacing
  double exact_area;     // analytic area (0 = not checked against a formula)
};

std::vector<SolidCase> cases() {
  return {
      {"sphere", [] { return make_sphere(0.8, tilted_pose(Vec3(1, 2, 3))); }, 0.8, 0.03, 4 * EIGEN_PI * 0.64},
      {"box", [] { return make_box(Vec3(1.0, 0.4, 0.25), tilted_pose(Vec3(-5, 0, 2))); }, 1.0, 0.03,
       8 * (0.4 + 0.1 + 0.25)},
      {"cylinder", [] { return make_cylinder(0.5, 0.7, tilted_pose(Vec3(0, 0, 0))); }, 0.7, 0.03,
       2 * EIGEN_PI * 0.5 * 1.4 + 2 * EIGEN_PI * 0.25},
      {"torus", [] { return make_torus(1.0, 0.25, tilted_pose(Vec3(0, 7, 0))); }, 1.0, 0.03, 4 * EIGEN_PI * EIGEN_PI * 0.25},
      {"capsule", [] { return make_capsule(0.4, 0.5, tilted_pose(Vec3(2, 2, 2))); }, 0.9, 0.03,
       4 * EIGEN_PI * 0.16 + 4 * EIGEN_PI * 0.4 * 0.5},
      {"cup", [] { return make_cup(0.5, 1.0, 0.08, 0.25, 0.05, tilted_pose(Vec3(0, -3, 1))); }, 1.0, 0.02, 0.0},
  };
}

TEST(Scene, SamplesLieOnTheSurfaceWithExactUnitNormals) {
  for (const SolidCase& c : cases()) {
    SCOPED_TRACE(c.name);
    const auto solid = c.make();
    SampleParams sp;
    sp.spacing = c.spacing;
    const SampledSurfels s = solid->sample(sp);
    const Eigen::Index n = s.positions.rows();
    ASSERT_GT(n, 100);
    ASSERT_EQ(s.normals.rows(), n);
    ASSERT_EQ(s.radii.size(), n);
    ASSERT_EQ(static_cast<Eigen::Index>(s.part.size()), n);
    const double fd = 1e-6 * c.scale;  // finite-difference step, far below the distance to any edge
    int off_gradient = 0;
    double worst_sdf = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      const Vec3 p = s.positions.row(i).transpose();
      const Vec3 nrm = s.normals.row(i).transpose();
      worst_sdf = std::max(worst_sdf, std::abs(solid->sdf(p)));
      EXPECT_NEAR(nrm.norm(), 1.0, 1e-14);
      EXPECT_EQ(s.radii[i], c.spacing);
      Vec3 g;
      for (int d = 0; d < 3; ++d) {
        const Vec3 e = Vec3::Unit(d) * fd;
        g[d] = (solid->sdf(p + e) - solid->sdf(p - e)) / (2 * fd);
      }
      if ((g - nrm).norm() > 1e-6) ++off_gradient;
    }
    EXPECT_LT(worst_sdf, 1e-9 * c.scale);
    // Only samples within ~fd of a seam (cup: body/handle intersection curve) may see the other
    // piece's gradient; none are expected, one in ten thousand is tolerated.
    EXPECT_LE(off_gradient, n / 10000) << off_gradient << " normals differ from the SDF gradient";
  }
}

TEST(Scene, CountsFollowAreaOverSpacingSquared) {
  for (const SolidCase& c : cases()) {
    SCOPED_TRACE(c.name);
    const auto solid = c.make();
    if (c.exact_area > 0) {
      EXPECT_NEAR(solid->area(), c.exact_area, 1e-12 * c.exact_area);
    }
    for (double h : {c.spacing, 2 * c.spacing}) {
      SampleParams sp;
      sp.spacing = h;
      const double n = static_cast<double>(solid->sample(sp).positions.rows());
      const double expect = solid->area() / (h * h);
      std::cout << "[scene] " << c.name << " spacing " << h << ": " << n << " samples, area/h^2 = " << expect
                << "\n";
      EXPECT_NEAR(n / expect, 1.0, 0.08);
    }
  }
  // The cup's area (numerically integrated) lies between the body alone and body + full half tube.
  const double r = 0.5, h = 1.0, w = 0.08, ri = r - w;
  const double body = EIGEN_PI * r * r + 2 * EIGEN_PI * r * h + EIGEN_PI * (r * r - ri * ri) + 2 * EIGEN_PI * ri * (h - w) + EIGEN_PI * ri * ri;
  const double cup = make_cup()->area();
  EXPECT_GT(cup, body);
  EXPECT_LT(cup, body + 2 * EIGEN_PI * EIGEN_PI * 0.25 * 0.05);
}

TEST(Scene, NeighbourSpacingIsRoughlyUniform) {
  // Nearest-neighbour distance of every sample (brute force on a small sphere) stays within a
  // factor of the spacing: no clumps at the poles, no holes.
  const auto sphere = make_sphere(0.5);
  SampleParams sp;
  sp.spacing = 0.05;
  const SampledSurfels s = sphere->sample(sp);
  const Eigen::Index n = s.positions.rows();
  double lo = 1e9, hi = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double best = 1e9;
    for (Eigen::Index j = 0; j < n; ++j) {
      if (j != i) best = std::min(best, (s.positions.row(i) - s.positions.row(j)).norm());
    }
    lo = std::min(lo, best);
    hi = std::max(hi, best);
  }
  std::cout << "[scene] sphere nearest-neighbour distance in [" << lo << ", " << hi << "] for spacing 0.05\n";
  EXPECT_GT(lo, 0.1 * sp.spacing);
  EXPECT_LT(hi, 1.5 * sp.spacing);
}

TEST(Scene, SameSeedSameSamplesDifferentSeedDifferent) {
  for (const SolidCase& c : cases()) {
    SCOPED_TRACE(c.name);
    const auto solid = c.make();
    SampleParams a;
    a.spacing = 2 * c.spacing;
    a.seed = 42;
    SampleParams b = a;
    b.seed = 43;
    const SampledSurfels s1 = solid->sample(a), s2 = solid->sample(a), s3 = solid->sample(b);
    ASSERT_EQ(s1.positions.rows(), s2.positions.rows());
    EXPECT_TRUE(s1.positions == s2.positions);
    EXPECT_TRUE(s1.normals == s2.normals);
    EXPECT_FALSE(s1.positions.rows() == s3.positions.rows() && s1.positions == s3.positions);
  }
  // No jitter: box grids do not depend on the seed; revolved pieces still get seeded ring phases.
  SampleParams a, b;
  a.jitter = b.jitter = 0.0;
  b.seed = 99;
  const auto box = make_box(Vec3(0.3, 0.3, 0.3));
  EXPECT_TRUE(box->sample(a).positions == box->sample(b).positions);
}

TEST(Scene, PoseIsRotationThenTranslation) {
  const Pose pose = tilted_pose(Vec3(10, -20, 30));
  const auto local = make_cylinder(0.3, 0.5);
  const auto placed = make_cylinder(0.3, 0.5, pose);
  SampleParams sp;
  sp.spacing = 0.05;
  const SampledSurfels a = local->sample(sp), b = placed->sample(sp);
  ASSERT_EQ(a.positions.rows(), b.positions.rows());
  for (Eigen::Index i = 0; i < a.positions.rows(); ++i) {
    const Vec3 expect = pose.rotation * a.positions.row(i).transpose() + pose.translation;
    EXPECT_LT((b.positions.row(i).transpose() - expect).norm(), 1e-13);
    EXPECT_LT((b.normals.row(i).transpose() - pose.rotation * a.normals.row(i).transpose()).norm(), 1e-14);
  }
  // Exact analytic SDF values at known points of the placed solid.
  EXPECT_NEAR(placed->sdf(pose.translation), -0.3, 1e-14);
  EXPECT_NEAR(placed->sdf(pose.rotation * Vec3(0, 0, 0.9) + pose.translation), 0.4, 1e-13);
  EXPECT_NEAR(placed->sdf(pose.rotation * Vec3(0.6, 0, 0.9) + pose.translation), 0.5, 1e-13);
}

TEST(Scene, ExactSdfSpotChecks) {
  EXPECT_DOUBLE_EQ(make_sphere(2.0)->sdf(Vec3(0, 3, 0)), 1.0);
  EXPECT_DOUBLE_EQ(make_box(Vec3(1, 2, 3))->sdf(Vec3(0, 0, 0)), -1.0);
  EXPECT_DOUBLE_EQ(make_box(Vec3(1, 2, 3))->sdf(Vec3(4, 6, 0)), 5.0);  // corner region: 3-4-5
  EXPECT_DOUBLE_EQ(make_torus(2.0, 0.5)->sdf(Vec3(2, 0, 0)), -0.5);
  EXPECT_DOUBLE_EQ(make_torus(2.0, 0.5)->sdf(Vec3(0, 0, 0)), 1.5);
  EXPECT_DOUBLE_EQ(make_capsule(0.5, 1.0)->sdf(Vec3(0, 0, 3)), 1.5);
  EXPECT_DOUBLE_EQ(make_capsule(0.5, 1.0)->sdf(Vec3(2, 0, 0.3)), 1.5);
  const auto cup = make_cup(0.5, 1.0, 0.08, 0.25, 0.05);
  EXPECT_NEAR(cup->sdf(Vec3(0, 0, 0.5)), 0.42, 1e-15);   // in the cavity: nearest is the inner wall
  EXPECT_NEAR(cup->sdf(Vec3(0, 0, 0.04)), -0.04, 1e-15);  // in the base
  EXPECT_NEAR(cup->sdf(Vec3(0, 0.46, 0.5)), -0.04, 1e-15);  // mid-wall, away from the handle
  EXPECT_NEAR(cup->sdf(Vec3(0.75, 0, 0.5)), -0.05, 1e-15);  // centre of the handle's tube
  EXPECT_NEAR(cup->sdf(Vec3(0.5 + 0.25 + 0.05 + 0.1, 0, 0.5)), 0.1, 1e-15);
  EXPECT_NEAR(cup->sdf(Vec3(0, 0, 1.3)), std::hypot(0.42, 0.3), 1e-15);  // above: nearest is the rim's inner edge
}

TEST(Scene, BadDimensionsThrowNamingTheField) {
  auto expect_field = [](const std::function<void()>& f, const std::string& field) {
    try {
      f();
      ADD_FAILURE() << "no throw for " << field;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
      EXPECT_EQ(e.field(), field);
    }
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_field([] { make_sphere(0.0); }, "radius");
  expect_field([&] { make_sphere(nan); }, "radius");
  expect_field([] { make_box(Vec3(1, -1, 1)); }, "half_extents");
  expect_field([] { make_cylinder(1.0, 0.0); }, "half_height");
  expect_field([] { make_torus(1.0, 1.5); }, "minor_radius");
  expect_field([] { make_torus(-1.0, 0.5); }, "major_radius");
  expect_field([] { make_capsule(std::numeric_limits<double>::infinity(), 1.0); }, "radius");
  expect_field([] { make_cup(0.5, 1.0, 0.6); }, "wall");
  expect_field([] { make_cup(0.5, 1.0, 0.08, 0.25, 0.1); }, "handle_minor");
  expect_field([] { make_cup(0.5, 1.0, 0.08, 0.5, 0.05); }, "handle_major");
  Pose bad;
  bad.rotation(0, 0) = 2.0;
  expect_field([&] { make_sphere(1.0, bad); }, "pose.rotation");
  const auto s = make_sphere(1.0);
  SampleParams sp;
  sp.spacing = -0.1;
  expect_field([&] { s->sample(sp); }, "spacing");
  sp.spacing = 0.1;
  sp.jitter = 0.9;
  expect_field([&] { s->sample(sp); }, "jitter");
  sp.jitter = 0.1;
  sp.spacing = 1e-7;
  try {
    s->sample(sp);
    ADD_FAILURE() << "huge sample count accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::TooLarge);
  }
}

TEST(Scene, UnionDropsSamplesInsideOtherParts) {
  Scene scene;
  scene.add(make_sphere(0.5));
  Pose shifted;
  shifted.translation = Vec3(0.6, 0, 0);
  scene.add(make_sphere(0.5, shifted));
  SampleParams sp;
  sp.spacing = 0.03;
  const SampledSurfels s = scene.sample(sp);
  int in0 = 0, in1 = 0;
  for (Eigen::Index i = 0; i < s.positions.rows(); ++i) {
    const Vec3 p = s.positions.row(i).transpose();
    EXPECT_LT(std::abs(scene.sdf(p)), 1e-12);  // on the union's surface
    EXPECT_GE(scene.part(1 - s.part[i]).sdf(p), 0.0);
    in0 += s.part[i] == 0;
    in1 += s.part[i] == 1;
  }
  // Each sphere loses the cap of height 0.2 inside the other: area 2 pi r h = 0.2 pi of pi.
  const double each = (EIGEN_PI - 2 * EIGEN_PI * 0.5 * 0.2) / (sp.spacing * sp.spacing);
  EXPECT_NEAR(in0 / each, 1.0, 0.08);
  EXPECT_NEAR(in1 / each, 1.0, 0.08);
  Points q(2, 3);
  q << 0.3, 0, 0, 3, 0, 0;
  const Values all = scene.sdf(q);
  EXPECT_NEAR(all[0], -0.2, 1e-15);
  EXPECT_NEAR(all[1], 1.9, 1e-15);
  EXPECT_DOUBLE_EQ(scene.sdf(q, 0)[1], 2.5);
  EXPECT_THROW(scene.sdf(q, 2), Error);
}

TEST(Scene, DefaultSceneIsSlabBelowSphere) {
  const Scene scene = make_default_scene();
  ASSERT_EQ(scene.parts(), 2u);
  EXPECT_EQ(scene.part(0).kind(), "box");
  EXPECT_EQ(scene.part(1).kind(), "sphere");
  const SampledSurfels s = scene.sample(SampleParams{});
  std::cout << "[scene] default scene: " << s.positions.rows() << " surfels\n";
  EXPECT_GE(s.positions.rows(), 5000);
  EXPECT_LE(s.positions.rows(), 10000);
  double slab_top = -1e9, sphere_bottom = 1e9;
  for (Eigen::Index i = 0; i < s.positions.rows(); ++i) {
    if (s.part[i] == 0) slab_top = std::max(slab_top, s.positions(i, 2));
    if (s.part[i] == 1) sphere_bottom = std::min(sphere_bottom, s.positions(i, 2));
  }
  EXPECT_NEAR(slab_top, 0.15, 1e-12);
  EXPECT_GT(sphere_bottom, slab_top + 0.3);  // well separated
  EXPECT_NEAR(scene.part(1).sdf(Vec3(0, 0, 1.0)), -0.5, 1e-15);
}

}  // namespace
}  // namespace surfeledit
