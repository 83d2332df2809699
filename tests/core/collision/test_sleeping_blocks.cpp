// The row sweep's sleeping blocks (parallel_sweep.hpp, SleepingBlocks; RESULTS §84): with the displacement bound a
// session hands over, blocks of rows that stay inside their spheres are not read. Truth: the brute-force oracle
// (collision_oracle.hpp) on every step -- colliding rows, depths and Robust's queries -- while blocks sleep; a
// detector put back from an image equals one that never slept; a bound that is too small departs from the oracle
// (and a checked build refuses it); a bound that is not a finite number >= 0 is refused before anything changes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"
#include "expect_error.hpp"

namespace surfeledit {
namespace {

using ::surfeledit::testing::brute_displacement_bound;
using ::surfeledit::testing::params_of;
using ::surfeledit::testing::run_against_oracle;
using ::surfeledit::testing::ScriptStep;
using ::surfeledit::testing::TestScene;
using ::surfeledit::testing::slab_and_sphere;
using ::surfeledit::testing::slab_script;

// Small steps down and idle ones (where most blocks sleep), then the detector tests' script (down through the
// slab, turned, pulled back: where rows are tested and blocks wake).
std::vector<ScriptStep> slow_then_scripted() {
  std::vector<ScriptStep> s;
  for (int i = 0; i < 5; ++i) s.push_back({Vec3(0, 0, -0.004), 0.0});
  for (int i = 0; i < 3; ++i) s.push_back({Vec3::Zero(), 0.0});
  for (const ScriptStep& k : slab_script()) s.push_back(k);
  for (int i = 0; i < 3; ++i) s.push_back({Vec3::Zero(), 0.0});
  return s;
}

Index asleep_in(const ::surfeledit::testing::RunLog& log) {
  Index n = 0;
  for (const CollisionStats& s : log.stats) n += s.asleep;
  return n;
}

TEST(SleepingBlocks, AgreeWithTheOracleEveryStepWhileBlocksSleep) {
  for (auto a : {CollisionAlgorithm::Robust, CollisionAlgorithm::Temporal}) {
    for (int threads : {1, 2}) {
      for (bool edits : {false, true}) {
        const auto log = run_against_oracle(slab_and_sphere(), params_of(a, threads), slow_then_scripted(), edits, true);
        // Not vacuous: blocks slept, and the steps that moved rows into the slab tested some.
        EXPECT_GT(asleep_in(log), 0) << to_string(a) << " threads " << threads;
        Index tested = 0;
        for (const CollisionStats& s : log.stats) {
          EXPECT_LE(s.asleep + s.tested, s.deformable);
          tested += s.tested;
        }
        EXPECT_GT(tested, 0);
      }
      // Without a bound nothing sleeps.
      const auto log = run_against_oracle(slab_and_sphere(), params_of(a, threads), slow_then_scripted(), false, false);
      EXPECT_EQ(asleep_in(log), 0);
    }
  }
}

// Behind the hierarchies (the narrow phase's sweep with candidates): the same colliding set as without a bound.
TEST(SleepingBlocks, BehindAHierarchyEqualTheSweepWithoutABound) {
  for (auto a : {CollisionAlgorithm::Robust, CollisionAlgorithm::Temporal}) {
    HierarchyParams h;
    h.zero = ZeroHierarchy::Aabb;
    h.deformable = DeformableHierarchy::Aabb;
    h.tree.update = bvh::UpdateMode::Bounded;
    TestScene scene = slab_and_sphere();
    auto ref = CollisionDetector::create(params_of(a), h);
    auto det = CollisionDetector::create(params_of(a), h);
    ref->reset(scene.view());
    det->reset(scene.view());
    Values last = scene.radii;
    Index asleep = 0;
    ::surfeledit::testing::play_script(
        scene, slow_then_scripted(), false, [](const IndexList&) {}, [](const std::vector<bool>&) {},
        [&](std::size_t k, const Points& previous) {
          CollisionScene view = scene.view();
          view.displacement_bound = brute_displacement_bound(scene, previous, last);
          const CollisionResult got = det->detect(view, previous), want = ref->detect(scene.view(), previous);
          EXPECT_EQ(got.colliding, want.colliding) << to_string(a) << " step " << k;
          EXPECT_EQ(got.depths, want.depths) << to_string(a) << " step " << k;
          EXPECT_EQ(got.stats.tested, want.stats.tested) << to_string(a) << " step " << k;
          asleep += got.stats.asleep;
        });
    EXPECT_GT(asleep, 0) << to_string(a);
  }
}

// An image put back (undo) after blocks slept: every block wakes, and the steps after it equal those of a detector
// that never slept (no bound) given the same image and steps.
TEST(SleepingBlocks, AnImagePutBackWakesEveryBlock) {
  for (auto a : {CollisionAlgorithm::Robust, CollisionAlgorithm::Temporal}) {
    TestScene scene = slab_and_sphere();
    auto ref = CollisionDetector::create(params_of(a));
    auto det = CollisionDetector::create(params_of(a));
    ref->reset(scene.view());
    det->reset(scene.view());
    Values last = scene.radii;
    auto step = [&](const Vec3& t) {
      const Points previous = scene.positions;
      scene.move(t, Mat3::Identity(), Vec3::Zero());
      CollisionScene view = scene.view();
      view.displacement_bound = brute_displacement_bound(scene, previous, last);
      const CollisionResult got = det->detect(view, previous), want = ref->detect(scene.view(), previous);
      EXPECT_EQ(got.colliding, want.colliding) << to_string(a);
      EXPECT_EQ(got.stats.tested, want.stats.tested) << to_string(a);
      return got.stats.asleep;
    };
    for (int i = 0; i < 3; ++i) step(Vec3(0, 0, -0.004));
    EXPECT_GT(step(Vec3::Zero()), 0) << to_string(a);
    // Images before a long way down (into the slab), which is then taken back.
    const Points before = scene.positions;
    const auto det_image = det->save_image(nullptr), ref_image = ref->save_image(nullptr);
    ASSERT_TRUE(det_image && ref_image);
    for (int i = 0; i < 4; ++i) step(Vec3(0, 0, -0.12));
    det->restore_image(*det_image);
    ref->restore_image(*ref_image);
    scene.positions = before;
    // The first step after it sweeps every row; idle steps after that sleep again.
    EXPECT_EQ(step(Vec3::Zero()), 0) << to_string(a);
    EXPECT_GT(step(Vec3::Zero()), 0) << to_string(a);
    for (int i = 0; i < 6; ++i) step(Vec3(0, 0, -0.05));
  }
}

// A bound below the real displacement (0 while the sphere goes down into the slab): sleeping rows are not tested,
// so a release build departs from the oracle (what the oracle tests above would catch) and a checked build refuses
// the step (Internal, naming SleepingBlocks).
TEST(SleepingBlocks, ATooSmallBoundIsCaught) {
  TestScene scene = slab_and_sphere();
  auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
  auto ref = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
  det->reset(scene.view());
  ref->reset(scene.view());
  int differing = 0;
  bool refused = false;
  for (int i = 0; i < 14 && !refused; ++i) {
    const Points previous = scene.positions;
    scene.move(Vec3(0, 0, i < 2 ? 0.0 : -0.1), Mat3::Identity(), Vec3::Zero());
    CollisionScene view = scene.view();
    view.displacement_bound = 0.0;
    const CollisionResult want = ref->detect(scene.view(), previous);
    try {
      differing += det->detect(view, previous).colliding != want.colliding;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::Internal);
      EXPECT_EQ(e.field(), "SleepingBlocks") << e.what();
      refused = true;
    }
  }
#ifdef SURFELEDIT_CHECKED
  EXPECT_TRUE(refused);
#else
  EXPECT_FALSE(refused);
  EXPECT_GT(differing, 0);
#endif
}

// A bound that is negative or not finite: InvalidArgument naming it, the detector unchanged (the next step with a
// good bound equals a detector that never saw the bad one).
TEST(SleepingBlocks, ABadBoundIsRefusedAndChangesNothing) {
  TestScene scene = slab_and_sphere();
  auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
  auto ref = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
  det->reset(scene.view());
  ref->reset(scene.view());
  const Points previous = scene.positions;
  scene.move(Vec3(0, 0, -0.4), Mat3::Identity(), Vec3::Zero());
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    CollisionScene view = scene.view();
    view.displacement_bound = bad;
    testing_util::expect_error([&] { det->detect(view, previous); }, ErrorCode::InvalidArgument, "displacement_bound");
  }
  CollisionScene view = scene.view();
  view.displacement_bound = 0.8;
  const CollisionResult got = det->detect(view, previous), want = ref->detect(scene.view(), previous);
  EXPECT_EQ(got.colliding, want.colliding);
  EXPECT_EQ(got.stats.tested, want.stats.tested);
  EXPECT_GT(got.stats.tested, 0);
}

}  // namespace
}  // namespace surfeledit
