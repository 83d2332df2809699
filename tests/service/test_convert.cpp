// Conversions between the generated C types and the service's and core's types.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "service_test_support.hpp"
#include "surfeledit/service/convert.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(Convert, StatusNumbersEqualErrorCodes) {
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::InvalidArgument)), surfeledit_proto_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::NotFound)), surfeledit_proto_STATUS_NOT_FOUND);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Conflict)), surfeledit_proto_STATUS_CONFLICT);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::TooLarge)), surfeledit_proto_STATUS_TOO_LARGE);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Io)), surfeledit_proto_STATUS_IO);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Internal)), surfeledit_proto_STATUS_INTERNAL);
}

TEST(Convert, Selectors) {
  surfeledit_proto_Selector s{};
  s.kind = surfeledit_proto_SELECTOR_BOX;
  s.center = {1, 2, 3};
  s.half_extents = {0.5, 0.5, 0.5};
  const Selector box = to_core(s, "set_regions.one.selectors[0]");
  EXPECT_EQ(box.kind, Selector::Kind::Box);
  EXPECT_EQ(box.center, Vec3(1, 2, 3));
  EXPECT_EQ(box.half_extents, Vec3(0.5, 0.5, 0.5));

  s.kind = static_cast<surfeledit_proto_SelectorKind>(7);
  expect_error([&] { to_core(s, "sel"); }, ErrorCode::InvalidArgument, "sel.kind");
  s.kind = surfeledit_proto_SELECTOR_SPHERE;
  s.radius = -1.0;
  expect_error([&] { to_core(s, "sel"); }, ErrorCode::InvalidArgument, "sel");
}

TEST(Convert, RegionSpecs) {
  std::vector<uint64_t> ids = {3, 1, 2};
  std::vector<surfeledit_proto_Selector> sels(2);
  sels[0].kind = surfeledit_proto_SELECTOR_SPHERE;
  sels[0].radius = 1.0;
  sels[1].kind = surfeledit_proto_SELECTOR_SPHERE;
  sels[1].radius = std::numeric_limits<double>::infinity() * 0.0;  // NaN
  surfeledit_proto_RegionSpec r{};
  point_to(r.ids, ids);
  r.selectors._length = 1;
  r.selectors._buffer = sels.data();
  const RegionSpec spec = to_core(r, "set_regions.zero");
  EXPECT_EQ(spec.ids, (IdList{3, 1, 2}));
  ASSERT_EQ(spec.selectors.size(), 1u);
  EXPECT_DOUBLE_EQ(spec.selectors[0].radius, 1.0);
  r.selectors._length = 2;
  expect_error([&] { to_core(r, "set_regions.zero"); }, ErrorCode::InvalidArgument, "set_regions.zero.selectors[1]");
}

TEST(Convert, DeformParams) {
  surfeledit_proto_Deform d{};
  d.translation = {0, 0, 1};
  d.axis = {0, 1, 0};
  d.angle = 0.5;
  std::string blend;
  d.blend = const_cast<char*>(blend.c_str());
  DeformParams p = to_core(d, "deform");
  EXPECT_EQ(p.blend, Blend::Smooth);  // empty -> smooth
  EXPECT_FALSE(p.center.has_value());
  EXPECT_EQ(p.translation, Vec3(0, 0, 1));
  blend = "linear";
  d.blend = const_cast<char*>(blend.c_str());
  d.has_center = true;
  d.center = {1, 1, 1};
  p = to_core(d, "deform");
  EXPECT_EQ(p.blend, Blend::Linear);
  ASSERT_TRUE(p.center.has_value());
  EXPECT_EQ(*p.center, Vec3(1, 1, 1));
  blend = "wobbly";
  d.blend = const_cast<char*>(blend.c_str());
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.blend");
  blend = "smooth";
  d.blend = const_cast<char*>(blend.c_str());
  d.axis = {0, 0, 0};
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.");
  d.axis = {0, 0, 1};
  d.translation.x = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.");
}

TEST(Convert, PrefixedErrorsKeepCodeAndMessage) {
  try {
    rethrow_prefixed(Error(ErrorCode::NotFound, "ids", "id 7 is unknown"), "set_regions");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::NotFound);
    EXPECT_EQ(e.field(), "set_regions.ids");
    EXPECT_EQ(message_of(e), "id 7 is unknown");
  }
  try {
    rethrow_prefixed(Error(ErrorCode::Conflict, "deform.axis", "x"), "deform");
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "deform.axis");
  }
}

TEST(Convert, ReplyViewPresentsEveryField) {
  Reply r;
  r.client_id = "c";
  r.request_id = 42;
  r.status = Status::Conflict;
  r.field = "session";
  r.message = "m";
  r.version = 9;
  r.timings = {{"total", 1.5}, {"apply", 0.5}};
  StatePage page;
  page.full = true;
  page.total = 10;
  page.offset = 4;
  page.ids = {4, 5};
  page.positions = {1, 2, 3, 4, 5, 6};
  page.normals = {0, 0, 1, 0, 0, 1};
  page.radii = {0.1, 0.2};
  r.state = page;
  SessionInfo si;
  si.name = "s";
  si.surfels = 2;
  si.structures = {{"model", 100}};
  r.session_info = si;
  ServerInfo sv;
  sv.version = "0.1.0";
  sv.sessions = {"a", "b"};
  sv.max_chunk_surfels = 65536;
  r.server_info = sv;
  service::StepResult st;
  st.seq = 3;
  st.moved = 2;
  st.center = {1, 2, 3};
  r.step = st;

  const ReplyView view(r);
  const surfeledit_proto_Reply& m = *view.get();
  EXPECT_STREQ(m.client_id, "c");
  EXPECT_EQ(m.request_id, 42u);
  EXPECT_EQ(m.status, surfeledit_proto_STATUS_CONFLICT);
  EXPECT_STREQ(m.field, "session");
  EXPECT_EQ(m.version, 9u);
  ASSERT_EQ(m.timings._length, 2u);
  EXPECT_STREQ(m.timings._buffer[1].name, "apply");
  ASSERT_EQ(m.state._length, 1u);
  EXPECT_EQ(m.state._buffer[0].offset, 4u);
  ASSERT_EQ(m.state._buffer[0].positions._length, 6u);
  EXPECT_DOUBLE_EQ(m.state._buffer[0].positions._buffer[5], 6.0);
  EXPECT_EQ(m.state._buffer[0].removed._length, 0u);
  ASSERT_EQ(m.session_info._length, 1u);
  EXPECT_STREQ(m.session_info._buffer[0].structures._buffer[0].name, "model");
  ASSERT_EQ(m.server_info._length, 1u);
  ASSERT_EQ(m.server_info._buffer[0].sessions._length, 2u);
  EXPECT_STREQ(m.server_info._buffer[0].sessions._buffer[1], "b");
  ASSERT_EQ(m.step._length, 1u);
  EXPECT_DOUBLE_EQ(m.step._buffer[0].center.z, 3.0);
  EXPECT_FALSE(m.timings._release);

  const Reply empty;
  const ReplyView none(empty);
  EXPECT_EQ(none.get()->state._length, 0u);
  EXPECT_EQ(none.get()->session_info._length, 0u);
  EXPECT_EQ(none.get()->server_info._length, 0u);
  EXPECT_EQ(none.get()->step._length, 0u);
}

TEST(Convert, StepResultsCarryEveryCollisionStat) {
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
  // Depths must match the colliding ids.
  core.depths.pop_back();
  EXPECT_THROW(to_reply(core, 6), std::logic_error);
}
