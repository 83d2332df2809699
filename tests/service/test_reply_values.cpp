// The core's results in the reply's form (reply_values.hpp), as written on the wire.
#include <gtest/gtest.h>

#include <stdexcept>

#include "service_test_support.hpp"
#include "surfeledit/service/reply_values.hpp"
#include "surfeledit/service/sample_views.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(ReplyValues, StepResultsCarryEveryCollisionStat) {
  surfeledit::StepResult core;
  core.moved = {1, 2};
  core.center = Vec3(1.0, 2.0, 3.0);
  core.detected = true;
  core.colliding = {4, 9};
  core.depths = {0.5, 0.25};
  core.inserted = {11};
  core.stats.deformable = 1;
  core.stats.tested = 2;
  core.stats.queries = 3;
  core.stats.colliding = 2;
  core.stats.detect_ms = 1.5;
  core.stats.preprocess_ms = 2.5;
  core.stats.nv = 7;
  core.stats.np = 8;
  core.stats.nu = 9;
  core.stats.asleep = 10;
  Reply r;
  r.step = to_reply(core, 5);
  const service::StepResult& st = *r.step;
  EXPECT_EQ(st.seq, 5u);
  EXPECT_EQ(st.moved, 2u);
  EXPECT_EQ(st.colliding, core.colliding);
  EXPECT_EQ(st.depths, core.depths);
  EXPECT_EQ(st.inserted, core.inserted);
  const ReplyView view(r);
  const surfeledit_proto_CollisionStats& ps = view.get()->step._buffer[0].stats;
  EXPECT_EQ(ps.deformable, 1u);
  EXPECT_EQ(ps.tested, 2u);
  EXPECT_EQ(ps.queries, 3u);
  EXPECT_EQ(ps.colliding, 2u);
  EXPECT_DOUBLE_EQ(ps.detect_ms, 1.5);
  EXPECT_DOUBLE_EQ(ps.preprocess_ms, 2.5);
  EXPECT_EQ(ps.nv, 7u);
  EXPECT_EQ(ps.np, 8u);
  EXPECT_EQ(ps.nu, 9u);
  EXPECT_EQ(ps.asleep, 10u);
  // Depths must match the colliding ids.
  core.depths.pop_back();
  EXPECT_THROW(to_reply(core, 6), std::logic_error);
}
