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
  rb.token = send(surfeledit_proto_OP_INVITE)->token;
  ASSERT_EQ(rb.token.size(), 32u);
  rb.client = "client-b";
  ASSERT_EQ(send(surfeledit_proto_OP_JOIN_SESSION)->session_info->clients, 2u);
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Ok);
  // client-b left a session that goes on: presence updates of the two joins and the leave, no close.
  ASSERT_EQ(updates.size(), 3u);
  EXPECT_EQ(updates[0].presence, "join");
  EXPECT_EQ(updates[1].presence, "join");
  EXPECT_EQ(updates[2].presence, "leave");
  EXPECT_EQ(updates[2].author, "client-b");
  updates.clear();
  rb.client = "client-a";
  ASSERT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Ok);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "close");
  const auto info = send(surfeledit_proto_OP_INFO);
  EXPECT_TRUE(info->server_info->sessions.empty());
  EXPECT_EQ(send(surfeledit_proto_OP_CLOSE_SESSION)->status, Status::Conflict);
}

// Privacy without DDS: the handler alone (sender 0) still keeps sessions private to their members.
TEST_F(HandlerTest, SessionsArePrivateAndRolesAreEnforced) {
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  rb.role = "viewer";
  const std::string viewer_token = send(surfeledit_proto_OP_INVITE)->token;
  rb.client = "client-b";
  // Not a member: the same NotFound as for a session that does not exist, and nothing listed.
  const auto denied = send(surfeledit_proto_OP_JOIN_SESSION);
  rb.session = "no-such-session";
  const auto missing = send(surfeledit_proto_OP_JOIN_SESSION);
  EXPECT_EQ(denied->status, Status::NotFound);
  EXPECT_EQ(denied->status, missing->status);
  EXPECT_EQ(denied->field, missing->field);
  rb.session = "s";
  rb.token = "0123456789abcdef0123456789abcdef";  // wrong token
  EXPECT_EQ(send(surfeledit_proto_OP_JOIN_SESSION)->status, Status::NotFound);
  const auto info = send(surfeledit_proto_OP_INFO);
  EXPECT_TRUE(info->server_info->sessions.empty());
  EXPECT_FALSE(info->session_info);
  EXPECT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Conflict);  // the name is taken
  // A viewer reads but never changes.
  rb.token = viewer_token;
  ASSERT_EQ(send(surfeledit_proto_OP_JOIN_SESSION)->status, Status::Ok);
  EXPECT_EQ(send(surfeledit_proto_OP_INFO)->server_info->sessions, std::vector<std::string>{"s"});
  rb.load_begin.total = 4;
  const auto refused = send(surfeledit_proto_OP_LOAD_BEGIN);
  EXPECT_EQ(refused->status, Status::PermissionDenied);
  EXPECT_EQ(refused->field, "session");
  EXPECT_EQ(send(surfeledit_proto_OP_INVITE)->status, Status::PermissionDenied);
  EXPECT_EQ(send(surfeledit_proto_OP_HISTORY)->status, Status::Ok);
}

// A repeated request id with another op is not answered from the cache.
TEST_F(HandlerTest, ARequestIdReusedForAnotherOpIsRefused) {
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION, 7)->status, Status::Ok);
  const auto r = send(surfeledit_proto_OP_INFO, 7);
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "request_id");
  EXPECT_EQ(r->request_op, static_cast<std::uint32_t>(surfeledit_proto_OP_INFO));
}
