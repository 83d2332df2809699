// Deformation tool (§1): blend functions and lambda fields vs brute force; the step's tests are in
// test_deformation_step.cpp.
#include <gtest/gtest.h>

#include <cmath>

#include "deformation_model.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

using namespace deformation_model;

TEST(Deformation, BlendFunctionsHitBothEnds) {
  for (Blend b : {Blend::Smooth, Blend::Quadratic, Blend::Linear}) {
    SCOPED_TRACE(to_string(b));
    EXPECT_EQ(parse_blend(to_string(b)), b);
    EXPECT_EQ(blend_value(b, 0.0), 0.0);  // F0 does not move
    EXPECT_EQ(blend_value(b, 1.0), 1.0);  // F1 moves fully
    double prev = 0.0;
    for (int k = 1; k < 100; ++k) {
      const double l = k / 100.0;
      const double v = blend_value(b, l);
      EXPECT_GT(v, prev);  // strictly increasing
      prev = v;
      const double fd = (blend_value(b, l + 1e-6) - blend_value(b, l - 1e-6)) / 2e-6;
      EXPECT_NEAR(blend_derivative(b, l), fd, 1e-7);
    }
  }
  // smooth: beta = E(1 - lambda), E(x) = (x^2 - 1)^2, flat at both ends.
  EXPECT_NEAR(blend_value(Blend::Smooth, 0.3), std::pow(0.7 * 0.7 - 1.0, 2), 1e-15);
  EXPECT_EQ(blend_derivative(Blend::Smooth, 0.0), 0.0);
  EXPECT_EQ(blend_derivative(Blend::Smooth, 1.0), 0.0);
  EXPECT_EQ(blend_value(Blend::Quadratic, 0.5), 0.25);
  try {
    parse_blend("cubic", "params.blend");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), "params.blend");
  }
}

TEST(Deformation, FieldsMatchBruteForce) {
  const Model m = make_model();
  const DeformationFields f = compute_fields(m.positions, m.regions, 2);
  const Eigen::Index n = m.positions.rows();
  const Values lam = f.lambda();
  const Points grad = f.grad_lambda();
  ASSERT_EQ(lam.size(), n);
  ASSERT_EQ(grad.rows(), n);
  ASSERT_EQ(f.blend.rows(), static_cast<Eigen::Index>(f.deformable.size()));
  std::size_t deformable = 0;
  int gradient_checked = 0, gradient_ok = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Region r = m.regions[static_cast<std::size_t>(i)];
    const Vec3 p = m.positions.row(i).transpose();
    if (r == Region::Zero) {
      EXPECT_EQ(lam[i], 0.0);
      EXPECT_TRUE(grad.row(i).isZero(0.0));
      continue;
    }
    ASSERT_LT(deformable, f.deformable.size());
    EXPECT_EQ(f.deformable[deformable++], i);
    if (r == Region::One) {
      EXPECT_EQ(lam[i], 1.0);
      EXPECT_TRUE(grad.row(i).isZero(0.0));
      continue;
    }
    EXPECT_NEAR(lam[i], brute_lambda(m, p), 1e-14);
    // Gradient vs central differences of the brute-force lambda (skipped where the nearest
    // F0/F1 surfel changes inside the stencil: lambda has a kink there).
    Index a0 = -1, a1 = -1;
    brute_distance(m, p, Region::Zero, &a0);
    brute_distance(m, p, Region::One, &a1);
    const double h = 1e-6;
    Vec3 fd;
    bool same = true;
    for (int d = 0; d < 3 && same; ++d) {
      for (double sg : {-1.0, 1.0}) {
        Index b0 = -1, b1 = -1;
        brute_distance(m, p + sg * h * Vec3::Unit(d), Region::Zero, &b0);
        brute_distance(m, p + sg * h * Vec3::Unit(d), Region::One, &b1);
        same = same && b0 == a0 && b1 == a1;
      }
      fd[d] = (brute_lambda(m, p + h * Vec3::Unit(d)) - brute_lambda(m, p - h * Vec3::Unit(d))) / (2 * h);
    }
    if (!same) continue;
    ++gradient_checked;
    gradient_ok += (grad.row(i).transpose() - fd).norm() <= 1e-6 * (1.0 + fd.norm());
  }
  EXPECT_EQ(deformable, f.deformable.size());
  EXPECT_GT(gradient_checked, 500);
  EXPECT_EQ(gradient_ok, gradient_checked);
  // Per-deformable-row storage only: a region byte per row, and an index and 4 doubles per deformable row.
  EXPECT_EQ(f.memory_bytes() >= static_cast<std::size_t>(n) + deformable * (sizeof(Index) + 4 * sizeof(double)), true);
  EXPECT_LT(f.memory_bytes(), static_cast<std::size_t>(n) * 2 + deformable * 2 * (sizeof(Index) + 4 * sizeof(double)));
}

// compute_fields(positions, regions) refuses the selection (Conflict), naming `row` as lying in both regions.
void expect_conflict(const Points& positions, const std::vector<Region>& regions, Index row) {
  try {
    compute_fields(positions, regions);
    ADD_FAILURE() << "overlapping regions accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Conflict);
    EXPECT_NE(std::string(e.what()).find("row " + std::to_string(row) + " "), std::string::npos) << e.what();
  }
}

TEST(Deformation, FieldsRejectOverlapAndEmptyRegions) {
  Model m = make_model(0.08);
  // Row 5 (a blend/zero/one row, whatever it is) duplicated: one copy F0, the other F1.
  const Eigen::Index n = m.positions.rows();
  Points pos(n + 1, 3);
  pos.topRows(n) = m.positions;
  pos.row(n) = m.positions.row(5);
  std::vector<Region> reg = m.regions;
  reg[5] = Region::Zero;
  reg.push_back(Region::One);
  expect_conflict(pos, reg, 5);
  // The mirror: row 5 in F1, its copy (the last row) in F0; the F1 row's own check must report it.
  reg[5] = Region::One;
  reg.back() = Region::Zero;
  expect_conflict(pos, reg, 5);
  auto expect_invalid = [](const Points& p, const std::vector<Region>& r) {
    try {
      compute_fields(p, r);
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    }
  };
  std::vector<Region> no_zero(m.regions.size(), Region::Blend);
  no_zero[0] = Region::One;
  expect_invalid(m.positions, no_zero);
  std::vector<Region> no_one(m.regions.size(), Region::Zero);
  expect_invalid(m.positions, no_one);
  expect_invalid(m.positions, std::vector<Region>(3, Region::Zero));  // size mismatch
  Points bad = m.positions;
  bad(2, 2) = std::nan("");
  expect_invalid(bad, m.regions);
}

// A model tilted as a whole, so that compute_fields' trees search in a turned frame (KdTreeParams::align), and far
// from its regions (the sphere's rows above the slab): lambda and its gradient against brute force, the gradient from
// the analytic form with the brute-force nearest surfels wherever those are unique by a clear margin; and a surfel in
// both regions is still reported.
TEST(Deformation, FieldsOfATiltedModelMatchBruteForce) {
  Model m = sphere_over_slab(3);
  const Mat3 turn = Eigen::AngleAxisd(0.6, Vec3(1.0, 0.7, 0.3).normalized()).toRotationMatrix();
  m.positions = (m.positions * turn.transpose()).eval();
  m.normals = (m.normals * turn.transpose()).eval();
  const Vec3 up = turn.col(2);  // the slab's normal after the turn
  const Eigen::Index n = m.positions.rows();
  IndexList slab;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (m.regions[static_cast<std::size_t>(i)] == Region::Zero) {
      slab.push_back(static_cast<Index>(i));
    } else if (m.positions.row(i).dot(up.transpose()) < 0.8) {  // the sphere's lower half blends
      m.regions[static_cast<std::size_t>(i)] = Region::Blend;
    }
  }
  // The slab's tree is turned (what this test is about), not kept in world axes.
  KdTreeParams aligned;
  aligned.align = true;
  ASSERT_FALSE(KdTree(m.positions, slab, aligned).axes().isIdentity(1e-3));

  const DeformationFields f = compute_fields(m.positions, m.regions, 2);
  const Values lam = f.lambda();
  const Points grad = f.grad_lambda();
  int blend = 0, gradient_checked = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Region r = m.regions[static_cast<std::size_t>(i)];
    if (r != Region::Blend) {
      EXPECT_EQ(lam[i], r == Region::One ? 1.0 : 0.0);
      continue;
    }
    ++blend;
    const Vec3 p = m.positions.row(i).transpose();
    Index a0 = -1, a1 = -1;
    const double d0 = brute_distance(m, p, Region::Zero, &a0), d1 = brute_distance(m, p, Region::One, &a1);
    EXPECT_NEAR(lam[i], d0 / (d0 + d1), 1e-14);
    // The second nearest of each region more than 1e-9 farther: the nearest is unique and the gradient defined.
    auto second = [&](Region region, Index first) {
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index j = 0; j < n; ++j)
        if (m.regions[static_cast<std::size_t>(j)] == region && j != first)
          best = std::min(best, (m.positions.row(j).transpose() - p).norm());
      return best;
    };
    if (second(Region::Zero, a0) - d0 <= 1e-9 || second(Region::One, a1) - d1 <= 1e-9) continue;
    const Vec3 e0 = p - m.positions.row(a0).transpose(), e1 = p - m.positions.row(a1).transpose();
    const Vec3 expected = ((d1 / d0) * e0 - (d0 / d1) * e1) / ((d0 + d1) * (d0 + d1));
    ++gradient_checked;
    EXPECT_LE((grad.row(i).transpose() - expected).norm(), 1e-12 * (1.0 + expected.norm())) << "row " << i;
  }
  EXPECT_GT(blend, 500);
  EXPECT_GT(gradient_checked, blend / 2);

  // A slab row repeated as an F1 row: both regions hold that position.
  Points pos(n + 1, 3);
  pos.topRows(n) = m.positions;
  pos.row(n) = m.positions.row(slab[7]);
  std::vector<Region> reg = m.regions;
  reg.push_back(Region::One);
  expect_conflict(pos, reg, slab[7]);
}

TEST(Deformation, FieldsOfALargeModelOnTwoThreadsEqualOneThread) {
  // Large enough for the two trees to be built at once (server/core/src/at_once.hpp: kAtOnceMinPoints rows): the
  // same fields bit for bit as one thread's, and lambda on a sample of the blend rows against brute force.
  const Model m = make_model(0.012);
  ASSERT_GE(m.positions.rows(), 16384);
  const DeformationFields one = compute_fields(m.positions, m.regions, 1);
  const DeformationFields two = compute_fields(m.positions, m.regions, 2);
  EXPECT_EQ(one.deformable, two.deformable);
  ASSERT_EQ(one.blend.rows(), two.blend.rows());
  EXPECT_TRUE(one.blend.cwiseEqual(two.blend).all());
  const Values lam = two.lambda();
  int checked = 0;
  for (Eigen::Index i = 0; i < m.positions.rows(); i += 97) {
    if (m.regions[static_cast<std::size_t>(i)] != Region::Blend) continue;
    EXPECT_NEAR(lam[i], brute_lambda(m, m.positions.row(i).transpose()), 1e-14);
    ++checked;
  }
  EXPECT_GT(checked, 20);
}
}  // namespace
}  // namespace surfeledit
