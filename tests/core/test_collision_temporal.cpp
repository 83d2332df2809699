// Temporal Coherence (§4.3): every step equals a brute-force re-implementation of the same definition
// (spheres included), also across insertion and removal; threads do not change the result; the exact queries'
// start from each point's last winner leaf changes nothing, bit for bit.
#include <gtest/gtest.h>

#include "collision_scripts.hpp"

namespace surfeledit {
namespace {

using testing::run_against_oracle;
using testing::slab_and_sphere;
using testing::slab_script;

CollisionParams temporal(int threads = 1) {
  CollisionParams p;
  p.algorithm = CollisionAlgorithm::Temporal;
  p.threads = threads;
  return p;
}

TEST(CollisionTemporal, EqualsOracleEveryStep) {
  for (bool bound : {true, false}) {
    CollisionParams p = temporal();
    p.step_bound = bound;
    const auto log = run_against_oracle(slab_and_sphere(), p, slab_script(), false);
    std::size_t most = 0;
    for (const auto& c : log.colliding) most = std::max(most, c.size());
    EXPECT_GT(most, 20u);
    for (const auto& s : log.stats) EXPECT_EQ(s.tested, s.queries);
  }
}

TEST(CollisionTemporal, InsertionAndRemovalMidScenario) {
  run_against_oracle(slab_and_sphere(), temporal(), slab_script(), true);
}

TEST(CollisionTemporal, ThreadsGiveIdenticalResults) {
  const auto one = run_against_oracle(slab_and_sphere(0.05), temporal(1), slab_script(), true);
  const auto two = run_against_oracle(slab_and_sphere(0.05), temporal(2), slab_script(), true);
  EXPECT_EQ(one.colliding, two.colliding);
  EXPECT_EQ(one.depths, two.depths);
}

// With knn_eps == 0 each point's query starts at its last winner's leaf (a zero tree with cells); with a knn_eps
// so small that 1 + eps == 1 the tree has no cells and every query is the root descent, exact too. The two must
// give the same colliding rows, depths (bits) and work at every step, across insertion and removal.
TEST(CollisionTemporal, LeafStartEqualsTheRootDescentEveryStep) {
  CollisionParams root = temporal();
  root.knn_eps = 1e-300;
  ASSERT_EQ(1.0 + root.knn_eps, 1.0);
  for (bool churn : {false, true}) {
    const auto from_leaf = run_against_oracle(slab_and_sphere(0.05), temporal(), slab_script(), churn);
    const auto from_root = run_against_oracle(slab_and_sphere(0.05), root, slab_script(), churn);
    ASSERT_EQ(from_leaf.colliding.size(), from_root.colliding.size());
    for (std::size_t k = 0; k < from_leaf.colliding.size(); ++k) {
      EXPECT_EQ(from_leaf.colliding[k], from_root.colliding[k]) << "step " << k;
      EXPECT_EQ(from_leaf.depths[k], from_root.depths[k]) << "step " << k;  // bit for bit
      EXPECT_EQ(from_leaf.stats[k].tested, from_root.stats[k].tested) << "step " << k;
    }
  }
}

TEST(CollisionTemporal, SkipsSurfelsInsideTheirSpheres) {
  const auto log = run_against_oracle(slab_and_sphere(), temporal(), slab_script(), false);
  Index tested = 0, deformable = 0;
  for (const auto& s : log.stats) {
    tested += s.tested;
    deformable += s.deformable;
  }
  EXPECT_LT(tested, deformable);
  ::testing::Test::RecordProperty("tested_fraction_percent", static_cast<int>(100.0 * tested / deformable));
}

}  // namespace
}  // namespace surfeledit
