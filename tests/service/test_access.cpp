// Roles granted to authenticated users (access.hpp: Grant, parse_grant, request_partition,
// granted_role) and their use by OP_JOIN_SESSION (Command::subject).
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "handler_fixture.hpp"
#include "surfeledit/service/access.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(Grants, ParseUserRoleAndSession) {
  const Grant all = parse_grant("bob=editor");
  EXPECT_EQ(all.user, "bob");
  EXPECT_EQ(all.role, Role::Editor);
  EXPECT_TRUE(all.session.empty());
  const Grant one = parse_grant("carol_2=viewer:shared:x");  // the session is everything after the first ':'
  EXPECT_EQ(one.user, "carol_2");
  EXPECT_EQ(one.role, Role::Viewer);
  EXPECT_EQ(one.session, "shared:x");
  for (const char* bad : {"bob", "=editor", "bob=owner", "bob=", "bo.b=editor", "bob=editor:", "b*=viewer"}) {
    EXPECT_THROW(parse_grant(bad), std::invalid_argument) << bad;
  }
  EXPECT_THROW(parse_grant(std::string(65, 'a') + "=viewer"), std::invalid_argument);
}

TEST(Grants, RequestPartitionNamesOnlyAValidUser) {
  EXPECT_EQ(request_partition("bob"), "surfeledit.req.bob");
  EXPECT_EQ(request_partition_user(request_partition("bob")), "bob");
  for (const char* p : {"", "surfeledit.req.", "surfeledit.req.*", "surfeledit.req.a.b", "surfeledit.reply.bob",
                        "xsurfeledit.req.bob"}) {
    EXPECT_EQ(request_partition_user(p), "") << p;
  }
}

TEST(Grants, StrongestApplicableRoleAndNoneWithoutSubject) {
  const std::vector<Grant> g{parse_grant("bob=viewer"), parse_grant("bob=editor:s"), parse_grant("carol=viewer:t")};
  EXPECT_EQ(granted_role(g, "bob", "s"), Role::Editor);
  EXPECT_EQ(granted_role(g, "bob", "other"), Role::Viewer);
  EXPECT_EQ(granted_role(g, "carol", "t"), Role::Viewer);
  EXPECT_FALSE(granted_role(g, "carol", "s"));
  EXPECT_FALSE(granted_role(g, "", "s"));  // no authenticated subject: nothing granted
  EXPECT_FALSE(granted_role(g, "dave", "s"));
}

class GrantTest : public HandlerTest {
 protected:
  GrantTest() {
    HandlerConfig c{4, 1000, 1};
    c.grants = {parse_grant("bob=editor:s"), parse_grant("carol=viewer")};
    handler_ = std::make_unique<Handler>(c);
  }
  std::shared_ptr<const Reply> send_as(const std::string& subject, surfeledit_proto_Op op) {
    Command command = decode(rb.make(op, next_id++));
    command.subject = subject;
    return handler_->handle(command, updates);
  }
  std::unique_ptr<Handler> handler_;
};

TEST_F(GrantTest, GrantedSubjectsJoinInTheirRoleOthersGetNotFound) {
  rb.client = "alice.1";
  ASSERT_EQ(send_as("alice", surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  // dave: authenticated, nothing granted; bob without his subject (default partition): refused alike.
  rb.client = "dave.1";
  const auto dave = send_as("dave", surfeledit_proto_OP_JOIN_SESSION);
  EXPECT_EQ(dave->status, Status::NotFound);
  rb.client = "bob.0";
  EXPECT_EQ(send_as("", surfeledit_proto_OP_JOIN_SESSION)->status, Status::NotFound);
  rb.client = "bob.1";
  const auto bob = send_as("bob", surfeledit_proto_OP_JOIN_SESSION);
  ASSERT_EQ(bob->status, Status::Ok) << bob->message;
  rb.load_begin.total = 4;
  EXPECT_EQ(send_as("bob", surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);  // an editor changes it
  EXPECT_EQ(send_as("bob", surfeledit_proto_OP_INVITE)->status, Status::PermissionDenied);  // not the owner
  rb.client = "carol.1";
  ASSERT_EQ(send_as("carol", surfeledit_proto_OP_JOIN_SESSION)->status, Status::Ok);
  const auto refused = send_as("carol", surfeledit_proto_OP_LOAD_BEGIN);
  EXPECT_EQ(refused->status, Status::PermissionDenied);  // a viewer never changes it
  // bob's grant names session "s" only.
  rb.client = "alice.1";
  rb.session = "t";
  ASSERT_EQ(send_as("alice", surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  rb.client = "bob.1";
  EXPECT_EQ(send_as("bob", surfeledit_proto_OP_JOIN_SESSION)->status, Status::NotFound);
}
