// Robust's first test of a point (its inside state forgotten: kFirstUpdate) re-derives that state at the
// point's last free position only when the nearest original surfel to its new position is a zero surfel
// (robust_kernel.hpp, RESULTS §50). Two hand-built scenes, each against the brute-force oracle: one where
// that query is provably useless (nearest: a deformable surfel) and is skipped, and one where it decides the
// result (nearest: a zero surfel, the old inside state differs from the default) and must be made; and a random
// scene whose old-position queries (searched from the leaf the tree's descent reaches first, not from the root)
// land in many leaves.
#include <gtest/gtest.h>

#include <random>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"

namespace surfeledit {
namespace {

using namespace testing;

// A rigid plane z = 0 (normals +z, `spacing` apart, radii 0.05, side x side surfels) and the deformable rows `at`.
TestScene plane_and(const std::vector<Vec3>& at, int side = 21, double spacing = 0.1) {
  TestScene s;
  const Index n = side * side + static_cast<Index>(at.size());
  s.positions.resize(n, 3);
  s.normals.resize(n, 3);
  s.radii.resize(n);
  Index r = 0;
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j, ++r) {
      s.positions.row(r) << spacing * (i - side / 2), spacing * (j - side / 2), 0.0;
      s.normals.row(r) << 0.0, 0.0, 1.0;
      s.radii[r] = 0.05;
      s.regions.push_back(Region::Zero);
    }
  }
  for (const Vec3& p : at) {
    s.positions.row(r) = p.transpose();
    s.normals.row(r) << 0.0, 0.0, 1.0;
    s.radii[r] = 0.05;
    s.regions.push_back(Region::One);
    ++r;
  }
  return s;
}

// One step moving row `row` to `to` (the other rows stay); the detector's and the oracle's results must agree.
CollisionResult step_both(TestScene& scene, Index row, const Vec3& to, CollisionDetector& det, Oracle& oracle) {
  const Points previous = scene.positions;
  scene.positions.row(row) = to.transpose();
  const CollisionResult got = det.detect(scene.view(), previous);
  std::vector<double> depths;
  const IndexList want = oracle.detect(scene, previous, &depths);
  EXPECT_EQ(got.colliding, want);
  EXPECT_EQ(got.depths, depths);
  return got;
}

// Row D starts at height 1 (its sphere: the plane's distance less half a radius); a second deformable row E
// stays at (1.2, 0, 1.05). D moves to (1.2, 0, 1): it leaves its sphere and its nearest original surfel is E's
// (0.05 away, the plane 1.0): no change of inside state can count, so its old position is not queried.
TEST(CollisionRobustFirstUpdate, SkippedWhenTheNearestIsDeformable) {
  TestScene scene = plane_and({Vec3(0.0, 0.0, 1.0), Vec3(1.2, 0.0, 1.05)});
  const Index d = scene.rows() - 2;
  for (double w : {0.0, 0.01}) {
    CollisionParams p = params_of(CollisionAlgorithm::Robust);
    p.threshold = w;
    TestScene run = scene;
    auto det = CollisionDetector::create(p);
    det->reset(run.view());
    Oracle oracle(p);
    oracle.reset(run);
    const CollisionResult got = step_both(run, d, Vec3(1.2, 0.0, 1.0), *det, oracle);
    EXPECT_EQ(got.stats.tested, 1);
    EXPECT_EQ(got.stats.queries, 1);  // the position's query only (2 before the skip)
    EXPECT_TRUE(got.colliding.empty());
  }
}

// Row D starts under the plane at (0, 0, -0.5): at its old position its nearest original surfel is its own
// (distance 0, inside iff 0 < W: inside with W = 0.01). It moves to (0, 0, -0.02), out of its sphere (0.475),
// where the nearest is the plane's surfel (0.02 away) and it is inside again: no change, not colliding. The
// old position's query must be made: without it the inside state would default to "outside" and the point
// would be reported colliding.
TEST(CollisionRobustFirstUpdate, MadeWhenTheNearestIsZero) {
  TestScene scene = plane_and({Vec3(0.0, 0.0, -0.5)});
  const Index d = scene.rows() - 1;
  CollisionParams p = params_of(CollisionAlgorithm::Robust);
  p.threshold = 0.01;
  auto det = CollisionDetector::create(p);
  det->reset(scene.view());
  Oracle oracle(p);
  oracle.reset(scene);
  const CollisionResult got = step_both(scene, d, Vec3(0.0, 0.0, -0.02), *det, oracle);
  EXPECT_EQ(got.stats.tested, 1);
  EXPECT_EQ(got.stats.queries, 2);
  EXPECT_TRUE(got.colliding.empty());
  // The same move from above the plane with W = 0 (outside at the old position): the change counts.
  p.threshold = 0.0;
  TestScene above = plane_and({Vec3(0.0, 0.0, 0.5)});
  auto det2 = CollisionDetector::create(p);
  det2->reset(above.view());
  Oracle oracle2(p);
  oracle2.reset(above);
  const CollisionResult hit = step_both(above, d, Vec3(0.0, 0.0, -0.02), *det2, oracle2);
  EXPECT_EQ(hit.stats.queries, 2);
  EXPECT_EQ(hit.colliding, IndexList{d});
}

// A 41 x 41 plane (the original tree has ~35 leaves of <= 48 points) and 300 deformable points scattered within
// 0.3 of it, all with random normals, each moved every step by up to 0.4 per axis (fixed seed): the first tests
// after the reset re-derive the inside states at the reset positions, far from the points' new leaves, and every
// step must agree with the brute-force oracle (colliding rows, depths bit for bit).
TEST(CollisionRobustFirstUpdate, OldPositionsSearchedFromTheirNearPathLeafMatchTheOracle) {
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> at;
  for (int i = 0; i < 300; ++i) at.emplace_back(1.0 * u(rng), 1.0 * u(rng), 0.3 * u(rng));
  TestScene scene = plane_and(at, 41, 0.05);
  // Random unit normals: an inside state then depends on which surfel is the nearest, not only on the side.
  for (Index k = 0; k < scene.rows(); ++k) scene.normals.row(k) = Vec3(u(rng), u(rng), u(rng)).normalized().transpose();
  const CollisionParams p = params_of(CollisionAlgorithm::Robust);
  auto det = CollisionDetector::create(p);
  det->reset(scene.view());
  Oracle oracle(p);
  oracle.reset(scene);
  const Index first = scene.rows() - static_cast<Index>(at.size());
  Index rederived = 0;
  for (int step = 0; step < 6; ++step) {
    const Points previous = scene.positions;
    for (Index k = first; k < scene.rows(); ++k) scene.positions.row(k) += 0.4 * Vec3(u(rng), u(rng), u(rng)).transpose();
    const CollisionResult got = det->detect(scene.view(), previous);
    std::vector<double> depths;
    const IndexList want = oracle.detect(scene, previous, &depths);
    ASSERT_EQ(got.colliding, want) << "step " << step;
    ASSERT_EQ(got.depths, depths) << "step " << step;
    rederived += got.stats.queries - got.stats.tested;
  }
  EXPECT_GT(rederived, 50);  // old-position queries were made
}

}  // namespace
}  // namespace surfeledit
