// Replies presented as generated C samples (sample_views.hpp).
#include <gtest/gtest.h>

#include "service_test_support.hpp"
#include "surfeledit/service/sample_views.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(SampleViews, ReplyViewPresentsEveryField) {
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
