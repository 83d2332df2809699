// Simple (§4.1) and Improved Simple (§4.2): every step equals a brute-force re-implementation of the
// same definition; threads do not change the result; spatial coherence saves queries.
#include <gtest/gtest.h>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"

namespace surfeledit {
namespace {

using namespace testing;

TEST(CollisionSimple, EqualsOracleEveryStep) {
  for (bool boundary : {true, false}) {
    for (bool bound : {true, false}) {
      CollisionParams p = params_of(CollisionAlgorithm::Simple);
      p.boundary = boundary;
      p.step_bound = bound;
      const auto log = run_against_oracle(slab_and_sphere(), p, slab_script(), false);
      std::size_t most = 0;
      for (const auto& c : log.colliding) most = std::max(most, c.size());
      EXPECT_GT(most, 20u);  // the scenario does collide
      for (const auto& s : log.stats) EXPECT_EQ(s.queries, s.deformable);
    }
  }
}

TEST(CollisionSimple, ThresholdAndBoundaryParametersFollowTheOracle) {
  CollisionParams p = params_of(CollisionAlgorithm::Simple);
  p.threshold = 0.02;
  p.boundary_n = 4;
  p.boundary_i = 2;
  run_against_oracle(slab_and_sphere(), p, slab_script(), false);
}

// Zero and deformable surfels interleaved (every 5th slab surfel deformable, every 4th sphere surfel rigid), so that
// deformable surfels have their first zero neighbour at every rank: the marks come only from rows with a zero
// surfel among their n + 1 nearest (ZeroSet::rows_near_zero skips the others), as the oracle's brute force finds.
TEST(CollisionSimple, BoundaryMarksOnInterleavedRegionsFollowTheOracle) {
  TestScene scene = slab_and_sphere();
  for (Index r = 0; r < scene.rows(); ++r) {
    Region& g = scene.regions[static_cast<std::size_t>(r)];
    if (g == Region::Zero && r % 5 == 0) g = Region::One;
    else if (g != Region::Zero && r % 4 == 0) g = Region::Zero;
  }
  for (CollisionAlgorithm alg : {CollisionAlgorithm::Simple, CollisionAlgorithm::Improved, CollisionAlgorithm::Temporal}) {
    for (const auto& [n, i] : {std::pair{10, 5}, std::pair{4, 2}, std::pair{16, 16}}) {
      CollisionParams p = params_of(alg);
      p.boundary_n = n;
      p.boundary_i = i;
      run_against_oracle(scene, p, slab_script(), false);
    }
  }
}

TEST(CollisionSimple, InsertionAndRemovalMidScenario) {
  run_against_oracle(slab_and_sphere(), params_of(CollisionAlgorithm::Simple), slab_script(), true);
}

TEST(CollisionSimple, ThreadsGiveIdenticalResults) {
  const auto one = run_against_oracle(slab_and_sphere(), params_of(CollisionAlgorithm::Simple, 1), slab_script(), true);
  const auto two = run_against_oracle(slab_and_sphere(), params_of(CollisionAlgorithm::Simple, 2), slab_script(), true);
  EXPECT_EQ(one.colliding, two.colliding);
  EXPECT_EQ(one.depths, two.depths);
}

TEST(CollisionImproved, EqualsOracleEveryStep) {
  for (bool bound : {true, false}) {
    CollisionParams p = params_of(CollisionAlgorithm::Improved);
    p.step_bound = bound;
    run_against_oracle(slab_and_sphere(), p, slab_script(), false);
  }
}

TEST(CollisionImproved, InsertionAndRemovalMidScenario) {
  run_against_oracle(slab_and_sphere(), params_of(CollisionAlgorithm::Improved), slab_script(), true);
}

TEST(CollisionImproved, SpatialCoherenceSavesQueries) {
  const auto simple = run_against_oracle(slab_and_sphere(), params_of(CollisionAlgorithm::Simple), slab_script(), false);
  const auto improved =
      run_against_oracle(slab_and_sphere(), params_of(CollisionAlgorithm::Improved), slab_script(), false);
  Index qs = 0, qi = 0;
  for (std::size_t k = 0; k < simple.stats.size(); ++k) {
    qs += simple.stats[k].queries;
    qi += improved.stats[k].queries;
    EXPECT_EQ(improved.stats[k].tested, improved.stats[k].queries);
  }
  EXPECT_LT(qi, qs);
  ::testing::Test::RecordProperty("simple_queries", qs);
  ::testing::Test::RecordProperty("improved_queries", qi);
}

TEST(CollisionSimple, BoundaryMarksSuppressSeamSurfels) {
  // One plank, left half rigid: right after reset nothing moved, and without the boundary heuristic
  // the deformable surfels next to the seam are classified inside the open zero region.
  auto plank = make_box(Vec3(1.0, 0.3, 0.1));
  const SampledSurfels s = plank->sample(SampleParams{0.05, 1, 0.25});
  testing::TestScene t;
  t.positions = s.positions;
  t.normals = s.normals;
  t.radii = s.radii;
  for (Index r = 0; r < t.rows(); ++r) t.regions.push_back(s.positions(r, 0) < 0.0 ? Region::Zero : Region::One);
  for (bool boundary : {true, false}) {
    CollisionParams p = params_of(CollisionAlgorithm::Simple);
    p.boundary = boundary;
    p.step_bound = false;
    const auto log = run_against_oracle(t, p, {testing::ScriptStep{}}, false);
    if (boundary) {
      EXPECT_TRUE(log.colliding[0].empty());
    } else {
      EXPECT_FALSE(log.colliding[0].empty());
    }
  }
}

TEST(CollisionDetector, FactoryAndValidation) {
  EXPECT_EQ(CollisionDetector::create(params_of(CollisionAlgorithm::None)), nullptr);
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Improved, CollisionAlgorithm::Temporal,
                 CollisionAlgorithm::Robust}) {
    auto d = CollisionDetector::create(params_of(a));
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->params().algorithm, a);
    EXPECT_EQ(parse_algorithm(to_string(a)), a);
  }
  CollisionParams bad;
  bad.boundary_n = 0;
  try {
    CollisionDetector::create(bad);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), "boundary_n");
  }
  bad = CollisionParams{};
  bad.boundary_i = 11;
  EXPECT_THROW(validate(bad), Error);
  bad = CollisionParams{};
  bad.threshold = std::nan("");
  EXPECT_THROW(validate(bad), Error);
  EXPECT_THROW(parse_algorithm("fast"), Error);
}

}  // namespace
}  // namespace surfeledit
