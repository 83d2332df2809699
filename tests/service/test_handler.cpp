// Handler::handle: the op table, idempotence (the request cache) and atomic failures.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "handler_fixture.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

namespace {

// The op names of proto/surfeledit.idl's `enum Op`, in order (their values are their positions).
std::vector<std::string> idl_op_names() {
  std::ifstream in(SURFELEDIT_IDL);
  std::stringstream text;
  text << in.rdbuf();
  // Without comments, the enum's body.
  const std::string idl = std::regex_replace(text.str(), std::regex("//[^\n]*"), "");
  std::smatch body;
  if (!std::regex_search(idl, body, std::regex("enum\\s+Op\\s*\\{([^}]*)\\}"))) return {};
  std::vector<std::string> names;
  const std::string members = body[1].str();
  const std::regex name("[A-Za-z_][A-Za-z0-9_]*");
  for (auto it = std::sregex_iterator(members.begin(), members.end(), name); it != std::sregex_iterator(); ++it) {
    names.push_back(it->str());
  }
  return names;
}

}  // namespace

TEST(OpTable, EveryOpOfTheIdlHasAHandler) {
  const std::vector<std::string> names = idl_op_names();
  ASSERT_FALSE(names.empty()) << "no enum Op in " << SURFELEDIT_IDL;
  EXPECT_EQ(names.size(), kOpCount);
  for (std::size_t i = 0; i < names.size(); ++i) {
    surfeledit_proto_Request request{};
    request.op = static_cast<surfeledit_proto_Op>(i);
    const Command command = decode(request);
    EXPECT_TRUE(has_handler(command.op)) << names[i];
    EXPECT_EQ(op_name(command.op), names[i]);
  }
  EXPECT_FALSE(has_handler(static_cast<Op>(names.size())));
  EXPECT_EQ(op_name(static_cast<Op>(77)), "OP_77");
}

TEST_F(HandlerTest, ARepeatedRequestIsAnsweredAgainNotReapplied) {
  load(8);
  rb.load_begin.total = 4;
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
  ChunkArrays c = sphere_chunk(4);
  rb.load_chunk.offset = 0;
  point_to(rb.load_chunk.positions, c.positions);
  point_to(rb.load_chunk.normals, c.normals);
  point_to(rb.load_chunk.radii, c.radii);
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_CHUNK)->status, Status::Ok);
  const std::uint64_t commit_id = next_id++;
  const auto first = send(surfeledit_proto_OP_LOAD_COMMIT, commit_id);
  ASSERT_EQ(first->status, Status::Ok) << first->message;
  EXPECT_EQ(first->version, 2u);
  const std::size_t updates_after_first = updates.size();
  const auto again = send(surfeledit_proto_OP_LOAD_COMMIT, commit_id);
  EXPECT_EQ(again, first);  // the stored reply itself
  EXPECT_EQ(updates.size(), updates_after_first);  // nothing published again
  // A new id is a new request: there is no upload any more.
  const auto fresh = send(surfeledit_proto_OP_LOAD_COMMIT);
  EXPECT_EQ(fresh->status, Status::Conflict);
  EXPECT_EQ(fresh->version, 2u);
}

TEST_F(HandlerTest, ErrorsNameTheFieldAndChangeNothing) {
  load(8);
  const std::size_t n_updates = updates.size();
  // Missing argument sequence.
  surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_DEFORM, next_id++);
  req.deform._length = 0;
  auto r = handler.handle(decode(req), updates);
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "deform");
  // Deform without regions: Conflict from the core, version unchanged.
  rb.deform.translation = {0, 0, 1};
  r = send(surfeledit_proto_OP_DEFORM);
  EXPECT_NE(r->status, Status::Ok);
  EXPECT_EQ(r->version, 1u);
  // Unknown op.
  req = rb.make(static_cast<surfeledit_proto_Op>(77), next_id++);
  r = handler.handle(decode(req), updates);
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "op");
  // Another client may not touch the session before joining it.
  rb.client = "client-b";
  r = send(surfeledit_proto_OP_GET_STATE);
  EXPECT_EQ(r->status, Status::Conflict);
  EXPECT_EQ(r->field, "session");
  rb.session = "nope";
  r = send(surfeledit_proto_OP_JOIN_SESSION);
  EXPECT_EQ(r->status, Status::NotFound);
  EXPECT_EQ(updates.size(), n_updates);
}

TEST_F(HandlerTest, AMissingArgumentIsReportedBeforeTheSessionAndAnInvalidOneAfter) {
  load(8);
  rb.client = "client-b";  // not attached to "s"
  surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_DEFORM, next_id++);
  req.deform._length = 0;
  EXPECT_EQ(handler.handle(decode(req), updates)->field, "deform");
  rb.deform = surfeledit_proto_Deform{};
  rb.deform.axis = {0.0, 0.0, 1.0};
  rb.blend = "bogus";
  EXPECT_EQ(send(surfeledit_proto_OP_DEFORM)->field, "session");
  rb.client = "client-a";
  const auto r = send(surfeledit_proto_OP_DEFORM);
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "deform.blend");
}
