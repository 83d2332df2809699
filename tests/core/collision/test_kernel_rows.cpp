// A row detector's reset (kernel_rows.hpp, KernelRows::build_seeded) with threads > 1 on a large model runs parts that
// share nothing at once (at_once.hpp): Robust's original tree beside its seed, and Simple's and Temporal's zero tree
// beside the whole model's tree of the boundary marks (ZeroSetKernel::reset). Truth: the same detector reset on one
// thread, where they run one after the other: its saved state (references, marks, seeded spheres) byte for byte.
// (CollisionRobust / CollisionTemporal.ThreadsGiveIdenticalResults run two-thread detectors against the brute-force
// oracle on every step, on a smaller scene.) A reset that cannot be done throws its typed error from either path.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"
#include "expect_error.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit {
namespace {

using ::surfeledit::testing::params_of;
using ::surfeledit::testing::slab_and_sphere;
using ::surfeledit::testing::TestScene;

// The detector's state right after a reset on `threads` threads (CollisionDetector::save_state), but its time.
std::string state_after_reset(const TestScene& scene, CollisionAlgorithm algorithm, int threads) {
  auto det = CollisionDetector::create(params_of(algorithm, threads));
  det->reset(scene.view());
  EXPECT_TRUE(det->snapshottable());
  SnapshotWriter w;
  det->save_state(w);
  // The reset's time is the one value that differs (RowDetector::save_state ends with it, a double, then 20 bytes
  // of counts): zeroed.
  std::string bytes = w.bytes();
  EXPECT_GT(bytes.size(), 28u);
  bytes.replace(bytes.size() - 28, 8, 8, '\0');
  return bytes;
}

// The slab and a ball sunk into it, so that deformable surfels have zero surfels among their nearest (boundary marks).
TestScene ball_in_slab(double spacing) {
  Pose at;
  at.translation = Vec3(0, 0, 0.55);
  return ::surfeledit::testing::make_test_scene(*make_box(Vec3(1.5, 1.5, 0.15)), *make_sphere(0.5, at), spacing);
}

TEST(KernelRows, PartsAtOnceEqualOneAfterTheOther) {
  for (const TestScene& scene : {slab_and_sphere(0.03), ball_in_slab(0.025)}) {
    // Large enough for the parts at once: at least server/core/src/at_once.hpp's kAtOnceMinPoints rows.
    ASSERT_GE(scene.rows(), 16384);
    for (CollisionAlgorithm algorithm : {CollisionAlgorithm::Robust, CollisionAlgorithm::Temporal, CollisionAlgorithm::Simple}) {
      const std::string one = state_after_reset(scene, algorithm, 1);
      EXPECT_GT(one.size(), 1000u);
      for (int threads : {2, 3}) {
        const std::string other = state_after_reset(scene, algorithm, threads);
        const auto diff = std::mismatch(one.begin(), one.end(), other.begin(), other.end());
        EXPECT_TRUE(one == other) << enum_name(algorithm) << ", " << scene.rows() << " rows, threads " << threads << ": "
                                  << one.size() << " and " << other.size() << " bytes, first difference at "
                                  << (diff.first - one.begin());
      }
    }
  }
}

TEST(KernelRows, AResetWithoutZeroRowsThrowsOnEveryThreadCount) {
  TestScene scene = slab_and_sphere(0.025);
  for (Region& r : scene.regions) r = r == Region::Zero ? Region::Blend : r;
  for (CollisionAlgorithm algorithm : {CollisionAlgorithm::Robust, CollisionAlgorithm::Temporal}) {
    for (int threads : {1, 2}) {
      auto det = CollisionDetector::create(params_of(algorithm, threads));
      testing_util::expect_error([&] { det->reset(scene.view()); }, ErrorCode::InvalidArgument, "regions");
    }
  }
}

}  // namespace
}  // namespace surfeledit
