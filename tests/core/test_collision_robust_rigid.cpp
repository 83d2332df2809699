// Robust's original model reads its zero rows from the model and keeps no copy of them (issue 14,
// memory): when another tool moves rigid rows, CollisionDetector::on_rigid_moved is told where they were
// (`before`). Truth: a brute-force classification of every deformable point against the original model
// (the moved zero plane and the deformable surfels where they were at reset), computed here from the
// geometry; and a detector handed the wrong old values, which must miss what the right ones find.
#include <gtest/gtest.h>

#include <limits>

#include "surfeledit/core/collision.hpp"

namespace surfeledit {
namespace {

// A zero plane z = 0 over [0, 2]^2 (normals +z: the solid is below it) and a deformable grid at z = 3 over
// [0.5, 1.5]^2 (normals +z), all radii 0.04.
struct PlaneScene {
  Points positions, normals;
  Values radii;
  std::vector<Region> regions;
  IndexList zero, deformable;

  PlaneScene() {
    std::vector<Vec3> p;
    for (int i = 0; i <= 40; ++i)
      for (int j = 0; j <= 40; ++j) p.emplace_back(0.05 * i, 0.05 * j, 0.0);
    const std::size_t plane = p.size();
    for (int i = 0; i <= 10; ++i)
      for (int j = 0; j <= 10; ++j) p.emplace_back(0.5 + 0.1 * i, 0.5 + 0.1 * j, 3.0);
    const Index n = static_cast<Index>(p.size());
    positions.resize(n, 3);
    normals.resize(n, 3);
    radii = Values::Constant(n, 0.04);
    for (Index r = 0; r < n; ++r) {
      positions.row(r) = p[static_cast<std::size_t>(r)].transpose();
      normals.row(r) = Vec3(0, 0, 1).transpose();
      const bool z = static_cast<std::size_t>(r) < plane;
      regions.push_back(z ? Region::Zero : Region::One);
      (z ? zero : deformable).push_back(r);
    }
  }
  CollisionScene scene() const { return {positions, normals, radii, regions}; }
};

// Robust's answer for every deformable point, from the geometry alone: the points were outside the rigid
// part at their last test (above the plane, nearest original surfel a zero one), so a point collides iff
// its nearest original surfel (brute force over the plane where it is now and the deformable rows at
// reset) is a zero surfel it is inside of.
IdList brute_force(const PlaneScene& now, const Points& original_deformable) {
  IdList out;
  for (Index r : now.deformable) {
    const Vec3 p = now.positions.row(r).transpose();
    double best = std::numeric_limits<double>::infinity();
    bool zero = false, inside = false;
    for (Index z : now.zero) {
      const Vec3 q = now.positions.row(z).transpose();
      const double d2 = (p - q).squaredNorm();
      if (d2 < best) best = d2, zero = true, inside = (p - q).dot(now.normals.row(z).transpose()) < 0.0;
    }
    for (Eigen::Index d = 0; d < original_deformable.rows(); ++d) {
      const double d2 = (p - original_deformable.row(d).transpose()).squaredNorm();
      if (d2 < best) best = d2, zero = false;
    }
    if (zero && inside) out.push_back(r);
  }
  return out;
}

// Resets on `s`, brings the deformable grid down to z = 0.2 (outside, tested), moves the plane up by `lift`,
// follows it with `before` = where the plane was (or, with `wrong`, where it is now), and returns the next
// step's colliding rows (no deformable motion).
IdList follow(double lift, bool wrong, PlaneScene& s, Points& original_deformable) {
  CollisionParams params;
  params.algorithm = CollisionAlgorithm::Robust;
  params.threads = 1;
  auto detector = CollisionDetector::create(params);
  detector->reset(s.scene());
  original_deformable.resize(static_cast<Eigen::Index>(s.deformable.size()), 3);
  for (std::size_t d = 0; d < s.deformable.size(); ++d)
    original_deformable.row(static_cast<Eigen::Index>(d)) = s.positions.row(s.deformable[d]);
  Points previous = s.positions;
  for (Index r : s.deformable) s.positions(r, 2) = 0.2;
  EXPECT_TRUE(detector->detect(s.scene(), previous).colliding.empty());
  RigidRows before;
  const auto nz = static_cast<Eigen::Index>(s.zero.size());
  before.positions.resize(nz, 3);
  before.normals.resize(nz, 3);
  before.radii.resize(nz);
  for (Eigen::Index j = 0; j < nz; ++j) {
    const Index r = s.zero[static_cast<std::size_t>(j)];
    if (!wrong) before.positions.row(j) = s.positions.row(r);
    s.positions(r, 2) += lift;
    if (wrong) before.positions.row(j) = s.positions.row(r);
    before.normals.row(j) = s.normals.row(r);
    before.radii[j] = s.radii[r];
  }
  EXPECT_TRUE(detector->on_rigid_moved(s.scene(), s.zero, before));
  previous = s.positions;
  const CollisionResult result = detector->detect(s.scene(), previous);
  IdList out(result.colliding.begin(), result.colliding.end());
  return out;
}

TEST(RobustRigid, ThePlaneLiftedOverThePointsIsFoundWithTheOldValues) {
  // Lifted by 0.5 the plane passes every point (0.3 above them, beyond their spheres of 0.18): only the
  // reach of the move (old vs new positions) selects them for a test.
  PlaneScene s;
  Points original;
  const IdList found = follow(0.5, false, s, original);
  const IdList truth = brute_force(s, original);
  EXPECT_EQ(truth.size(), s.deformable.size());  // not vacuous: every point is under the plane now
  EXPECT_EQ(found, truth);
}

TEST(RobustRigid, WrongOldValuesMissWhatTheRightOnesFind) {
  PlaneScene s;
  Points original;
  const IdList found = follow(0.5, true, s, original);
  const IdList truth = brute_force(s, original);
  EXPECT_FALSE(truth.empty());
  EXPECT_NE(found, truth);  // the test above would fail with these values
}

TEST(RobustRigid, ASmallLiftAgreesWithTheBruteForceToo) {
  // Lifted by 0.1 the plane ends inside the points' spheres (selected by the sphere test, whatever the reach).
  PlaneScene s;
  Points original;
  const IdList found = follow(0.1, false, s, original);
  EXPECT_EQ(found, brute_force(s, original));
}

TEST(RobustRigid, MemoryHoldsNoCopyOfTheZeroRows) {
  // 1,681 zero rows and 121 deformable ones: the copy is the deformable rows' 56 bytes each; a copy of the
  // zero rows would add 1,681 x 56 = 94 kB.
  PlaneScene s;
  CollisionParams params;
  params.algorithm = CollisionAlgorithm::Robust;
  auto robust = CollisionDetector::create(params);
  robust->reset(s.scene());
  const std::size_t rows = s.regions.size();
  // Tree (points 24 B, rows 4 B, nodes) of every row, the deformable copy and states; far below 56 B per zero row more.
  EXPECT_LT(robust->memory_bytes(), rows * 40 + s.deformable.size() * (56 + 64 + 8));
}

}  // namespace
}  // namespace surfeledit
