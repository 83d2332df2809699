// Deformation step (§1): rigid ends of a step, normals/tangents vs a finite-difference Jacobian, validation,
// invariance under similarity, large angles, `only` and the displacement bound.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>

#include "deformation_model.hpp"
#include "surfeledit/core/deformation.hpp"

namespace surfeledit {
namespace {

using namespace deformation_model;


TEST(Deformation, ZeroRegionStillOneRegionRigid) {
  Model m = make_model();
  const DeformationFields f = compute_fields(m.positions, m.regions);
  const Values lam = f.lambda();
  const Model before = m;
  DeformParams p;
  p.translation = Vec3(0.1, -0.05, 0.2);
  p.axis = Vec3(1, 1, 0);
  p.angle = 0.3;
  const DeformResult r = apply_step(f, p, m.positions, m.normals, &m.tu, &m.tv);
  const Vec3 c = f1_centroid(before);
  EXPECT_LT((r.center - c).norm(), 1e-14);
  const Mat3 rot = Eigen::AngleAxisd(p.angle, p.axis.normalized()).toRotationMatrix();
  double worst_f1 = 0.0;
  std::size_t k = 0;
  for (Eigen::Index i = 0; i < m.positions.rows(); ++i) {
    const Region reg = m.regions[static_cast<std::size_t>(i)];
    const double s = blend_value(p.blend, lam[i]);
    if (s > 0) {
      ASSERT_LT(k, r.moved.size());
      EXPECT_EQ(r.moved[k++], i);
    }
    if (reg == Region::Zero) {  // bit-identical
      EXPECT_TRUE(m.positions.row(i) == before.positions.row(i));
      EXPECT_TRUE(m.normals.row(i) == before.normals.row(i));
      EXPECT_TRUE(m.tu.row(i) == before.tu.row(i));
      EXPECT_TRUE(m.tv.row(i) == before.tv.row(i));
    } else if (reg == Region::One) {
      const Vec3 expect = rot * (before.positions.row(i).transpose() - c) + c + p.translation;
      worst_f1 = std::max(worst_f1, (m.positions.row(i).transpose() - expect).norm());
      EXPECT_LT((m.normals.row(i).transpose() - rot * before.normals.row(i).transpose()).norm(), 1e-14);
      EXPECT_LT((m.tu.row(i).transpose() - rot * before.tu.row(i).transpose()).norm(), 1e-15);
      EXPECT_LT((m.tv.row(i).transpose() - rot * before.tv.row(i).transpose()).norm(), 1e-15);
    } else {
      const Vec3 expect = reference_map(before.positions.row(i).transpose(), s, p, c);
      EXPECT_LT((m.positions.row(i).transpose() - expect).norm(), 1e-14);
    }
    EXPECT_NEAR(m.normals.row(i).norm(), 1.0, 1e-14);
  }
  EXPECT_EQ(k, r.moved.size());
  EXPECT_LT(worst_f1, 1e-14);
}

TEST(Deformation, RigidWhenF1IsEverythingDeformable) {
  Model m = make_model(0.04, -0.3, -0.3);  // no blend rows
  for (Region r : m.regions) ASSERT_NE(r, Region::Blend);
  const DeformationFields f = compute_fields(m.positions, m.regions);
  const Model before = m;
  DeformParams p;
  p.translation = Vec3(0.3, 0.0, -0.1);
  p.axis = Vec3(0, 1, 2);
  p.angle = -0.8;
  p.center = Vec3(0.5, 0.5, 0.5);
  p.blend = Blend::Quadratic;
  const DeformResult r = apply_step(f, p, m.positions, m.normals, &m.tu, &m.tv);
  EXPECT_EQ(r.center, *p.center);
  EXPECT_EQ(r.moved, f.deformable);
  const Mat3 rot = Eigen::AngleAxisd(p.angle, p.axis.normalized()).toRotationMatrix();
  for (Index i : f.deformable) {
    const Vec3 expect = rot * (before.positions.row(i).transpose() - *p.center) + *p.center + p.translation;
    EXPECT_LT((m.positions.row(i).transpose() - expect).norm(), 1e-14);
    EXPECT_LT((m.normals.row(i).transpose() - rot * before.normals.row(i).transpose()).norm(), 1e-14);
  }
  // The moved part stays a rigid copy: pairwise distances are preserved.
  for (std::size_t k = 1; k < f.deformable.size(); k += 37) {
    const Index a = f.deformable[k - 1], b = f.deformable[k];
    EXPECT_NEAR((m.positions.row(a) - m.positions.row(b)).norm(),
                (before.positions.row(a) - before.positions.row(b)).norm(), 1e-14);
  }
}

TEST(Deformation, NormalsAndTangentsFollowTheFiniteDifferenceJacobian) {
  for (bool rotate : {false, true}) {
    SCOPED_TRACE(rotate ? "rotation + translation" : "translation only");
    Model m = make_model();
    const DeformationFields f = compute_fields(m.positions, m.regions);
    const Values lam = f.lambda();
    const Model before = m;
    DeformParams p;
    p.translation = Vec3(0.25, 0.1, 0.15);
    if (rotate) {
      p.axis = Vec3(0.3, -1, 0.2);
      p.angle = 0.6;
    }
    apply_step(f, p, m.positions, m.normals, &m.tu, &m.tv);
    const Vec3 c = f1_centroid(before);
    // F(x) with s from the brute-force lambda at x: the exact map the step samples.
    auto map = [&](const Vec3& x) { return reference_map(x, blend_value(p.blend, brute_lambda(before, x)), p, c); };
    int checked = 0, normal_ok = 0, tangent_ok = 0;
    for (Eigen::Index i = 0; i < m.positions.rows(); i += 3) {
      if (m.regions[static_cast<std::size_t>(i)] != Region::Blend) continue;
      const Vec3 x = before.positions.row(i).transpose();
      Index a0 = -1, a1 = -1;
      brute_distance(before, x, Region::Zero, &a0);
      brute_distance(before, x, Region::One, &a1);
      const double h = 1e-6;
      Mat3 jac;
      bool same = true;
      for (int d = 0; d < 3; ++d) {
        for (double sg : {-1.0, 1.0}) {
          Index b0 = -1, b1 = -1;
          brute_distance(before, x + sg * h * Vec3::Unit(d), Region::Zero, &b0);
          brute_distance(before, x + sg * h * Vec3::Unit(d), Region::One, &b1);
          same = same && b0 == a0 && b1 == a1;
        }
        jac.col(d) = (map(x + h * Vec3::Unit(d)) - map(x - h * Vec3::Unit(d))) / (2 * h);
      }
      if (!same) continue;
      ++checked;
      const Vec3 n0 = before.normals.row(i).transpose();
      // cofactor(J) n = det(J) J^-T n, oriented like R n.
      Vec3 expect_n = (jac.determinant() * jac.inverse().transpose() * n0).normalized();
      const Mat3 rot = Eigen::AngleAxisd(blend_value(p.blend, lam[i]) * p.angle,
                                         rotate ? p.axis.normalized() : Vec3::UnitZ())
                           .toRotationMatrix();
      if (expect_n.dot(rot * n0) < 0) expect_n = -expect_n;
      normal_ok += (m.normals.row(i).transpose() - expect_n).norm() < 1e-6;
      const Vec3 ju = jac * before.tu.row(i).transpose(), jv = jac * before.tv.row(i).transpose();
      tangent_ok += (m.tu.row(i).transpose() - ju).norm() < 1e-7 && (m.tv.row(i).transpose() - jv).norm() < 1e-7;
      // and the normal is the normalised cross product of the deformed tangents
      const Vec3 cross = m.tu.row(i).transpose().cross(m.tv.row(i).transpose()).normalized();
      EXPECT_LT((cross - m.normals.row(i).transpose()).norm(), 1e-12);
    }
    EXPECT_GT(checked, 100);
    EXPECT_EQ(normal_ok, checked);
    EXPECT_EQ(tangent_ok, checked);
  }
}

TEST(Deformation, NormalsStayUnitOverManySteps) {
  Model m = make_model();
  const DeformationFields f = compute_fields(m.positions, m.regions);
  DeformParams p;
  p.translation = Vec3(0.01, 0.02, -0.01);
  p.axis = Vec3(1, 0, 0);
  p.angle = 0.05;
  for (int step = 0; step < 50; ++step) apply_step(f, p, m.positions, m.normals, &m.tu, &m.tv);
  for (Eigen::Index i = 0; i < m.normals.rows(); ++i) {
    EXPECT_NEAR(m.normals.row(i).norm(), 1.0, 1e-14);
    ASSERT_TRUE(m.positions.row(i).allFinite());
  }
}

TEST(Deformation, ThreadsGiveIdenticalResults) {
  Model a = make_model(0.0034);  // fine enough that the step runs on two threads (kStepParallelMinMoved)
  Model b = a;
  const DeformationFields f = compute_fields(a.positions, a.regions);
  DeformParams p;
  p.translation = Vec3(0.1, 0.0, 0.1);
  p.angle = 0.4;
  p.axis = Vec3(0, 1, 0);
  const DeformResult ra = apply_step(f, p, a.positions, a.normals, &a.tu, &a.tv, 1);
  const DeformResult rb = apply_step(f, p, b.positions, b.normals, &b.tu, &b.tv, 2);
  EXPECT_GE(ra.moved.size(), kStepParallelMinMoved);
  EXPECT_EQ(ra.moved, rb.moved);
  EXPECT_TRUE(a.positions == b.positions);
  EXPECT_TRUE(a.normals == b.normals);
  EXPECT_TRUE(a.tu == b.tu);
}

TEST(Deformation, BadParamsThrowAndLeaveArraysUntouched) {
  Model m = make_model(0.08);
  const DeformationFields f = compute_fields(m.positions, m.regions);
  const Model before = m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto expect_rejected = [&](DeformParams p, const std::string& field, Points* tu, Points* tv, int threads) {
    try {
      apply_step(f, p, m.positions, m.normals, tu, tv, threads);
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
      EXPECT_EQ(e.field(), field);
    }
    EXPECT_TRUE(m.positions == before.positions);
    EXPECT_TRUE(m.normals == before.normals);
    EXPECT_TRUE(m.tu == before.tu);
    EXPECT_TRUE(m.tv == before.tv);
  };
  DeformParams p;
  p.translation = Vec3(nan, 0, 0);
  expect_rejected(p, "translation", &m.tu, &m.tv, 1);
  p = {};
  p.angle = std::numeric_limits<double>::infinity();
  expect_rejected(p, "angle", &m.tu, &m.tv, 1);
  p = {};
  p.angle = 0.1;
  p.axis = Vec3::Zero();
  expect_rejected(p, "axis", &m.tu, &m.tv, 1);
  p = {};
  p.center = Vec3(0, nan, 0);
  expect_rejected(p, "center", &m.tu, &m.tv, 1);
  p = {};
  p.blend = static_cast<Blend>(9);
  expect_rejected(p, "blend", &m.tu, &m.tv, 1);
  expect_rejected(DeformParams{}, "threads", &m.tu, &m.tv, -1);
  Points short_tv = m.tv.topRows(4);
  expect_rejected(DeformParams{}, "tangent_v", &m.tu, &short_tv, 1);
  // A zero axis is fine when nothing rotates.
  p = {};
  p.axis = Vec3::Zero();
  p.translation = Vec3(0, 0, 0.1);
  EXPECT_NO_THROW(apply_step(f, p, m.positions, m.normals));
  Points short_normals = m.normals.topRows(3);
  EXPECT_THROW(apply_step(f, p, m.positions, short_normals), Error);
  EXPECT_THROW(validate(DeformParams{Vec3::Zero(), Vec3(nan, 0, 0), 0.0, std::nullopt, Blend::Smooth}), Error);
}

// Runs three steps on the model placed by x -> scale * x + offset (translations scaled too) and
// returns the largest deviation after mapping back, relative to the model's diagonal.
struct Deviation {
  double position = 0.0;  // max |p - p_ref| / diagonal
  double normal = 0.0;    // max |n - n_ref|
};

Deviation run_similar(double scale, const Vec3& offset) {
  const Model base = make_model(0.04);
  Model ref = base, m = base;
  m.positions = (base.positions * scale).rowwise() + offset.transpose();
  const DeformationFields f_ref = compute_fields(ref.positions, ref.regions);
  const DeformationFields f = compute_fields(m.positions, m.regions);
  DeformParams p;
  p.axis = Vec3(1, -2, 0.5);
  p.angle = 0.35;
  p.translation = Vec3(0.1, 0.2, -0.05);
  DeformParams ps = p;
  ps.translation = p.translation * scale;
  for (int step = 0; step < 3; ++step) {
    apply_step(f_ref, p, ref.positions, ref.normals);
    apply_step(f, ps, m.positions, m.normals);
  }
  const double diag = (base.positions.colwise().maxCoeff() - base.positions.colwise().minCoeff()).norm();
  Deviation d;
  for (Eigen::Index i = 0; i < m.positions.rows(); ++i) {
    const Vec3 back = (m.positions.row(i).transpose() - offset) / scale;
    d.position = std::max(d.position, (back - ref.positions.row(i).transpose()).norm() / diag);
    d.normal = std::max(d.normal, (m.normals.row(i) - ref.normals.row(i)).norm());
  }
  return d;
}

TEST(Deformation, InvariantUnderTranslationAndScale) {
  struct Case {
    const char* name;
    double scale;
    Vec3 offset;
  };
  for (const Case& c : {Case{"translate 1e6", 1.0, Vec3(1e6, -1e6, 1e6)}, Case{"scale 1e-4", 1e-4, Vec3::Zero()},
                        Case{"scale 1e4", 1e4, Vec3::Zero()}}) {
    const Deviation d = run_similar(c.scale, c.offset);
    std::cout << "[deformation] " << c.name << ": position deviation " << d.position
              << " x diagonal, normal deviation " << d.normal << "\n";
    ::testing::Test::RecordProperty(std::string("invariance_") + c.name, std::to_string(d.position));
    EXPECT_LT(d.position, 1e-9) << c.name;
    EXPECT_LT(d.normal, 1e-6) << c.name;
  }
}

// Angles far from the polynomial's [-pi/4, pi/4] (the step reduces them by pi/2 in three parts): F1 turns
// rigidly by exactly the rotation Eigen's AngleAxis (libm's sin/cos) gives, and the blend band follows the
// reference map, up to |angle| = kMaxStepAngle.
TEST(Deformation, LargeAnglesMatchLibmRotations) {
  const Model base = make_model(0.08);
  const DeformationFields f = compute_fields(base.positions, base.regions);
  const Values lam = f.lambda();
  const Vec3 c = f1_centroid(base);
  for (const double angle : {2.0, -3.5, 7.9, 100.25, -637.0, kMaxStepAngle, -kMaxStepAngle}) {
    Model m = base;
    DeformParams p;
    p.axis = Vec3(0.3, -1, 0.7);
    p.angle = angle;
    p.center = c;
    apply_step(f, p, m.positions, m.normals, &m.tu, &m.tv);
    const Mat3 rot = Eigen::AngleAxisd(angle, p.axis.normalized()).toRotationMatrix();
    double worst = 0.0, worst_blend = 0.0;
    for (Eigen::Index i = 0; i < m.positions.rows(); ++i) {
      const Region reg = base.regions[static_cast<std::size_t>(i)];
      if (reg == Region::One) {
        const Vec3 expect = rot * (base.positions.row(i).transpose() - c) + c;
        worst = std::max(worst, (m.positions.row(i).transpose() - expect).norm());
        worst = std::max(worst, (m.normals.row(i).transpose() - rot * base.normals.row(i).transpose()).norm());
      } else if (reg == Region::Blend) {
        const Vec3 expect = reference_map(base.positions.row(i).transpose(), blend_value(p.blend, lam[i]), p, c);
        worst_blend = std::max(worst_blend, (m.positions.row(i).transpose() - expect).norm());
      }
    }
    EXPECT_LT(worst, 1e-13) << "angle " << angle;
    EXPECT_LT(worst_blend, 1e-12) << "angle " << angle;
  }
}

// `only` moves exactly the listed rows, each exactly as the full step moves it (same centre given).
TEST(Deformation, OnlyMovesTheListedRowsAsTheFullStepDoes) {
  const Model base = make_model(0.06);
  const DeformationFields f = compute_fields(base.positions, base.regions);
  DeformParams p;
  p.translation = Vec3(0.02, -0.01, 0.05);
  p.axis = Vec3(0, 1, 1);
  p.angle = 0.4;
  p.center = f1_centroid(base);
  Model full = base;
  apply_step(f, p, full.positions, full.normals, &full.tu, &full.tv);
  IndexList only;
  for (std::size_t k = 0; k < f.deformable.size(); k += 3) only.push_back(f.deformable[k]);  // every third
  Model part = base;
  const DeformResult r = apply_step(f, p, part.positions, part.normals, &part.tu, &part.tv, 1, &only);
  EXPECT_EQ(r.moved, only);
  std::vector<bool> listed(static_cast<std::size_t>(base.positions.rows()), false);
  for (const Index i : only) listed[static_cast<std::size_t>(i)] = true;
  for (Eigen::Index i = 0; i < base.positions.rows(); ++i) {
    const Model& expect = listed[static_cast<std::size_t>(i)] ? full : base;
    ASSERT_TRUE(part.positions.row(i) == expect.positions.row(i)) << "row " << i;
    ASSERT_TRUE(part.normals.row(i) == expect.normals.row(i)) << "row " << i;
    ASSERT_TRUE(part.tu.row(i) == expect.tu.row(i) && part.tv.row(i) == expect.tv.row(i)) << "row " << i;
  }
  // A row that is not deformable (F0) is refused, and nothing moves.
  IndexList bad = {only.front()};
  for (Eigen::Index i = 0; i < base.positions.rows(); ++i)
    if (base.regions[static_cast<std::size_t>(i)] == Region::Zero) {
      bad.push_back(static_cast<Index>(i));
      break;
    }
  std::sort(bad.begin(), bad.end());
  Model m = base;
  try {
    apply_step(f, p, m.positions, m.normals, &m.tu, &m.tv, 1, &bad);
    ADD_FAILURE() << "accepted a non-deformable row";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "only");
  }
  EXPECT_TRUE(m.positions == base.positions);
  EXPECT_TRUE(m.normals == base.normals);
}

// The step's displacement bound handed to the detector (displacement_bound): no row of a translation moves
// farther than it, on every blend, at 1e6 offsets (where rounding p + s t is most of a tiny step) and at
// 1e-4 / 1e4 scales, for steps from far below the coordinates' ulp to large; none with a rotation.
TEST(Deformation, DisplacementBoundHoldsForEveryRow) {
  const Model base = make_model();
  std::size_t checked = 0;
  for (const double scale : {1.0, 1e-4, 1e4}) {
    for (const Vec3 offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
      Points positions = base.positions * scale;
      positions.rowwise() += (offset * scale).transpose();
      const DeformationFields fields = compute_fields(positions, base.regions, 1);
      for (const Blend blend : {Blend::Smooth, Blend::Quadratic, Blend::Linear}) {
        for (const double length : {1e-13, 3e-11, 1e-7, 1e-3, 0.25}) {
          DeformParams p;
          p.blend = blend;
          p.translation = Vec3(0.6, -0.48, 0.64) * (length * scale);
          const std::optional<double> bound = displacement_bound(p);
          ASSERT_TRUE(bound.has_value());
          Points moved = positions, normals = base.normals;
          apply_step(fields, p, moved, normals, nullptr, nullptr, 1);
          double largest = 0.0;
          for (Eigen::Index i = 0; i < moved.rows(); ++i)
            largest = std::max(largest, (moved.row(i) - positions.row(i)).norm());
          EXPECT_LE(largest, *bound) << "scale " << scale << " offset " << offset.x() << " length " << length;
          if (length >= 1e-7) EXPECT_GT(largest, 0.0) << "the step moves rows (length " << length << ")";
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 90u);
  DeformParams turn;
  turn.angle = 0.1;
  EXPECT_FALSE(displacement_bound(turn).has_value());
}
}  // namespace
}  // namespace surfeledit
