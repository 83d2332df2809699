// A row detector's reset (kernel_rows.hpp, KernelRows::build_seeded): with threads > 1 a kernel whose seed reads
// nothing its reset writes (Robust) runs the two at once. Truth: the same detector reset on one thread, where they run
// one after the other: its saved state (original model, seeded spheres) byte for byte. (CollisionRobust.
// ThreadsGiveIdenticalResults runs a two-thread detector, reset so, against the brute-force oracle on every step.)
// A reset that cannot be done throws its typed error from either path.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

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
std::string state_after_reset(const TestScene& scene, int threads) {
  auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust, threads));
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

TEST(KernelRows, SeedBesideResetEqualsOneAfterTheOther) {
  for (double spacing : {0.03, 0.025}) {
    const TestScene scene = slab_and_sphere(spacing);
    // Large enough for the reset beside the seed: at least server/core/src/at_once.hpp's kAtOnceMinPoints rows.
    ASSERT_GE(scene.rows(), 16384);
    const std::string one = state_after_reset(scene, 1);
    EXPECT_GT(one.size(), 1000u);
    for (int threads : {2, 3}) {
      const std::string other = state_after_reset(scene, threads);
      const auto diff = std::mismatch(one.begin(), one.end(), other.begin(), other.end());
      EXPECT_TRUE(one == other) << "spacing " << spacing << ", threads " << threads << ": " << one.size() << " and "
                                << other.size() << " bytes, first difference at " << (diff.first - one.begin());
    }
  }
}

TEST(KernelRows, AResetWithoutZeroRowsThrowsOnEveryThreadCount) {
  TestScene scene = slab_and_sphere(0.08);
  for (Region& r : scene.regions) r = r == Region::Zero ? Region::Blend : r;
  for (int threads : {1, 2}) {
    auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust, threads));
    testing_util::expect_error([&] { det->reset(scene.view()); }, ErrorCode::InvalidArgument, "regions");
  }
}

}  // namespace
}  // namespace surfeledit
