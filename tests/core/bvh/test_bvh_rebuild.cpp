// Rebuild aside: a background rebuild of a 60k-surfel deformable tree while "steps" (refit +
// tree/tree query) run on this thread. No step waits for it (timed), no step sees a half-built
// tree (the adopted tree is checked whole; run under ThreadSanitizer with -DSURFELEDIT_TSAN=ON).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <random>

#include "bvh_test_util.hpp"
#include "surfeledit/core/bvh/rebuilder.hpp"
#include "surfeledit/core/bvh/traversal.hpp"

namespace {

using namespace bvh_test;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

TEST(BvhRebuild, BackgroundRebuildNeverBlocksASteps) {
  const int nd = 60000, nz = 20000;
  Points pd, pz;
  Values rd, rz;
  make_sheet(nd, 51, pd, rd, 0.5);
  make_sheet(nz, 52, pz, rz, 0.0);
  Points p(nd + nz, 3);
  p << pd, pz;
  Values r(nd + nz);
  r << rd, rz;
  IndexList def, zero;
  for (Index i = 0; i < nd; ++i) def.push_back(i);
  for (Index i = nd; i < nd + nz; ++i) zero.push_back(i);
  BvhParams params;
  params.update = UpdateMode::Hybrid;
  const Bvh<Aabb> zero_tree(p, r, zero);
  auto tree = std::make_unique<Bvh<Aabb>>(p, r, def, params);
  BvhRebuilder<Aabb> rebuilder;

  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto step = [&](int k) {
    // Deform: a gentle wave, then refit and one tree/tree query.
    for (Index i = 0; i < nd; ++i) p(i, 2) += 0.002 * std::sin(0.5 * k + 4.0 * p(i, 0));
    BvhCounters c = tree->refit(p, r);
    CollectRows narrow;
    collide(zero_tree, *tree, SatMode::Lite, narrow, c);
    return narrow.rows.size();
  };

  double max_step_ms = 0.0, max_poll_ms = 0.0, start_ms = 0.0, sum_idle_ms = 0.0;
  int steps_during = 0, idle_steps = 0, adopted = 0;
  for (int k = 0; k < 5; ++k) {  // steps without a rebuild, for comparison
    const auto t0 = Clock::now();
    step(k);
    sum_idle_ms += ms_since(t0);
    ++idle_steps;
  }
  // "End of a drag": rebuild aside from a snapshot (a copy) of the positions.
  auto t0 = Clock::now();
  ASSERT_TRUE(rebuilder.start(p, r, def, params, /*tag=*/1));
  start_ms = ms_since(t0);
  EXPECT_EQ(status_of(*tree, rebuilder), BvhStatus::Rebuilding);
  const auto rebuild_t0 = Clock::now();
  int k = 5;
  for (; k < 100000; ++k) {
    const auto s0 = Clock::now();
    std::uint64_t tag = 0;
    std::unique_ptr<Bvh<Aabb>> fresh = rebuilder.take(&tag);  // the step boundary: never waits
    max_poll_ms = std::max(max_poll_ms, ms_since(s0));
    if (fresh) {
      EXPECT_EQ(tag, 1u);
      // A complete tree: its boxes contain the snapshot's surfels -- the rows are the same and
      // only positions changed since, so adopt it and refit it to the current positions.
      ASSERT_EQ(fresh->surfel_count(), nd);
      EXPECT_FALSE(fresh->refit_since_build());
      tree = std::move(fresh);
      ++adopted;
      step(k);
      BvhCounters c;
      tree->touch_all(c);  // hybrid: visit the lazy levels too before inspecting every box
      EXPECT_TRUE(check_invariants(*tree, p, r));
      break;
    }
    step(k);
    const double ms = ms_since(s0);
    max_step_ms = std::max(max_step_ms, ms);
    ++steps_during;
  }
  const double rebuild_wall_ms = ms_since(rebuild_t0);
  std::printf("[ rebuild ] background build %.1f ms (worker), %.1f ms wall until adopted; start() %.2f ms "
              "(snapshot copy); %d steps ran meanwhile, max step %.2f ms (idle steps avg %.2f ms); "
              "max take() %.4f ms\n",
              rebuilder.last_build_ms(), rebuild_wall_ms, start_ms, steps_during, max_step_ms,
              sum_idle_ms / idle_steps, max_poll_ms);
  EXPECT_EQ(adopted, 1);
  EXPECT_GE(steps_during, 2) << "steps should keep running while the tree is rebuilt";
  EXPECT_LT(max_poll_ms, 5.0);
  // No step waited for the build: each step is much shorter than the build itself.
  EXPECT_LT(max_step_ms, rebuilder.last_build_ms());
  EXPECT_NE(status_of(*tree, rebuilder), BvhStatus::Rebuilding);
}

}  // namespace
