// GET_STATE pages.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "handler_fixture.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST_F(HandlerTest, StatePagesCoverTheModel) {
  load(10);
  rb.get_state = surfeledit_proto_GetState{};
  rb.get_state.max_count = 0;  // server limit: 4
  std::vector<std::uint64_t> ids;
  std::uint64_t total = 0;
  do {
    rb.get_state.offset = ids.size();
    const auto r = send(surfeledit_proto_OP_GET_STATE);
    ASSERT_EQ(r->status, Status::Ok) << r->message;
    ASSERT_TRUE(r->state);
    EXPECT_TRUE(r->state->full);
    EXPECT_LE(r->state->ids.size(), 4u);
    EXPECT_EQ(r->state->positions.size(), 3 * r->state->ids.size());
    total = r->state->total;
    ids.insert(ids.end(), r->state->ids.begin(), r->state->ids.end());
  } while (ids.size() < total);
  EXPECT_EQ(total, 10u);
  EXPECT_EQ(ids, handler.model_of("s")->ids());
  rb.get_state.offset = 11;
  EXPECT_EQ(send(surfeledit_proto_OP_GET_STATE)->field, "get_state.offset");
  // Nothing changed since the current version.
  rb.get_state = surfeledit_proto_GetState{};
  rb.get_state.changes_only = true;
  rb.get_state.since_version = 1;
  const auto r = send(surfeledit_proto_OP_GET_STATE);
  ASSERT_TRUE(r->state);
  EXPECT_EQ(r->state->total, 0u);
}
