// The session ops: INFO, OPEN_SESSION, JOIN_SESSION, CLOSE_SESSION.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "handler_fixture.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST_F(HandlerTest, InfoWithoutSession) {
  const auto r = send(surfeledit_proto_OP_INFO);
  EXPECT_EQ(r->status, Status::Ok);
  ASSERT_TRUE(r->server_info);
  EXPECT_EQ(r->server_info->max_chunk_surfels, 4u);
  EXPECT_EQ(r->version, 0u);
  ASSERT_FALSE(r->timings.empty());
  EXPECT_EQ(r->timings.back().first, "total");
}

TEST_F(HandlerTest, TheLastCloseDropsTheSession) {
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  rb.client = "client-b";
  ASSERT_EQ(send(surfeledit_proto_OP_JOIN_SESSION)->session_info->clients, 2u);
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Ok);
  EXPECT_TRUE(updates.empty());
  rb.client = "client-a";
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Ok);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "close");
  const auto info = send(surfeledit_proto_OP_INFO);
  EXPECT_TRUE(info->server_info->sessions.empty());
  EXPECT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Conflict);
}
