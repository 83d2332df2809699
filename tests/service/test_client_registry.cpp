// ClientRegistry and the handler's identity and lease handling: ids bound to the sending writer,
// refused from others without a reply, detached once their writer's lease ran out.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "handler_fixture.hpp"
#include "surfeledit/service/client_registry.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;
using namespace std::chrono_literals;

TEST(ClientRegistry, BindsAnIdToTheFirstWriterAndRefusesOthers) {
  ClientRegistry r(2);
  const auto t = LeaseClock::now();
  EXPECT_TRUE(r.admit("a", 11, t));
  EXPECT_TRUE(r.admit("a", 11, t));
  EXPECT_FALSE(r.admit("a", 12, t));  // another writer claims a's id
  EXPECT_TRUE(r.admit("b", 11, t));
  EXPECT_FALSE(r.admit("c", 11, t));  // writer 11 holds its maximum of 2 ids
  EXPECT_EQ(r.find("a")->requests, 2u);
  r.forget("a");
  EXPECT_TRUE(r.admit("a", 12, t));   // released ids can be bound again
}

TEST(ClientRegistry, RecoveredIdsAreBoundByTheirFirstRequestAndExpireWithoutOne) {
  ClientRegistry r(1);
  const auto t = LeaseClock::now();
  r.recovered("a", t);
  r.recovered("b", t);
  r.recovered("c", t + 1s);
  EXPECT_EQ(*r.next_expiry(2s), t + 2s);
  EXPECT_TRUE(r.admit("a", 7, t + 1s));   // the first writer binds the recovered id; its lease stops
  EXPECT_FALSE(r.admit("a", 8, t + 1s));  // and then holds it
  EXPECT_FALSE(r.admit("b", 7, t + 1s));  // writer 7 holds its maximum of 1 id
  EXPECT_EQ(r.expired(t + 2s, 2s), std::vector<std::string>{"b"});
  EXPECT_EQ(r.expired(t + 3s, 2s), (std::vector<std::string>{"b", "c"}));
  r.recovered("a", t);  // an id already known is left as it is
  EXPECT_EQ(r.find("a")->sender, 7u);
  EXPECT_FALSE(r.find("a")->gone_since);
}

TEST(ClientRegistry, LeasesRunFromTheLossOfTheWriterUntilItIsAliveAgain) {
  ClientRegistry r;
  const auto t = LeaseClock::now();
  r.admit("a", 1, t);
  r.admit("b", 2, t);
  EXPECT_FALSE(r.next_expiry(1s));
  r.writer_lost(1, t);
  r.writer_lost(1, t + 500ms);  // a second loss does not restart the lease
  EXPECT_EQ(*r.next_expiry(1s), t + 1s);
  EXPECT_TRUE(r.expired(t + 999ms, 1s).empty());
  EXPECT_EQ(r.expired(t + 1s, 1s), std::vector<std::string>{"a"});
  r.writer_alive(1);
  EXPECT_TRUE(r.expired(t + 5s, 1s).empty());
  r.writer_lost(2, t);
  r.admit("b", 2, t + 100ms);  // a request proves the writer alive
  EXPECT_TRUE(r.expired(t + 5s, 1s).empty());
}

namespace {

std::shared_ptr<const Reply> send_from(Handler& h, RequestBuilder& rb, surfeledit_proto_Op op, std::uint64_t id,
                                       std::uint64_t sender, std::vector<UpdateEvent>& updates) {
  Command c = decode(rb.make(op, id));
  c.sender = sender;
  return h.handle(c, updates);
}

}  // namespace

TEST(HandlerIdentity, ASpoofedIdGetsNoReplyAndCannotReachTheCache) {
  Handler h(HandlerConfig{4, 1000, 1});
  RequestBuilder rb;
  std::vector<UpdateEvent> updates;
  ASSERT_EQ(send_from(h, rb, surfeledit_proto_OP_OPEN_SESSION, 1, 100, updates)->status, Status::Ok);
  updates.clear();  // the presence update of the join
  // Another writer: a repeat of request 1 (a cache read), a close, and the victim's next id.
  EXPECT_EQ(send_from(h, rb, surfeledit_proto_OP_OPEN_SESSION, 1, 200, updates), nullptr);
  EXPECT_EQ(send_from(h, rb, surfeledit_proto_OP_CLOSE_SESSION, 5, 200, updates), nullptr);
  EXPECT_EQ(send_from(h, rb, surfeledit_proto_OP_INFO, 2, 200, updates), nullptr);
  EXPECT_TRUE(updates.empty());
  // The victim's request 2 is served as its own op, and it is still attached.
  const auto r = send_from(h, rb, surfeledit_proto_OP_CLOSE_SESSION, 2, 100, updates);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->status, Status::Ok);
  EXPECT_EQ(r->request_op, static_cast<std::uint32_t>(surfeledit_proto_OP_CLOSE_SESSION));
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "close");
}

TEST(HandlerIdentity, AnExpiredLeaseDetachesTheClientAndFreesItsUpload) {
  LeasedHandler lh(1ms, 1ms);
  Handler& h = lh.handler;
  RequestBuilder& rb = lh.rb;
  std::vector<UpdateEvent>& updates = lh.updates;
  ASSERT_EQ(send_from(h, rb, surfeledit_proto_OP_OPEN_SESSION, 1, 100, updates)->status, Status::Ok);
  rb.token = send_from(h, rb, surfeledit_proto_OP_INVITE, 2, 100, updates)->token;
  rb.client = "client-b";
  ASSERT_EQ(send_from(h, rb, surfeledit_proto_OP_JOIN_SESSION, 1, 300, updates)->status, Status::Ok);
  rb.load_begin.total = 8;
  rb.load_begin.has_radii = true;
  ASSERT_EQ(send_from(h, rb, surfeledit_proto_OP_LOAD_BEGIN, 2, 300, updates)->status, Status::Ok);
  ChunkArrays c = sphere_chunk(4, 0, 8);
  point_to(rb.load_chunk.positions, c.positions);
  point_to(rb.load_chunk.normals, c.normals);
  point_to(rb.load_chunk.radii, c.radii);
  ASSERT_EQ(send_from(h, rb, surfeledit_proto_OP_LOAD_CHUNK, 3, 300, updates)->status, Status::Ok);
  rb.client = "client-a";
  auto info = send_from(h, rb, surfeledit_proto_OP_INFO, 3, 100, updates);
  EXPECT_EQ(info->server_info->upload_bytes, 4u * 7 * sizeof(double));
  EXPECT_EQ(info->session_info->clients, 2u);
  EXPECT_FALSE(h.next_lease_check());
  h.writer_lost(300);
  ASSERT_TRUE(h.next_lease_check());
  std::this_thread::sleep_for(5ms);
  updates.clear();  // the presence updates of the joins
  EXPECT_EQ(h.expire_leases(updates), std::vector<std::string>{"client-b"});
  // client-a is still attached: the session stays; the expiry is a presence update about client-b.
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "presence");
  EXPECT_EQ(updates[0].presence, "expired");
  EXPECT_EQ(updates[0].author, "client-b");
  info = send_from(h, rb, surfeledit_proto_OP_INFO, 4, 100, updates);
  EXPECT_EQ(info->server_info->upload_bytes, 0u);
  EXPECT_EQ(info->session_info->clients, 1u);
  EXPECT_EQ(info->server_info->clients, 1u);
  // After the grace period the detached id lost its membership: rejoining needs a token again.
  std::this_thread::sleep_for(5ms);
  EXPECT_TRUE(h.expire_leases(updates).empty());
  rb.client = "client-b";
  rb.token.clear();
  EXPECT_EQ(send_from(h, rb, surfeledit_proto_OP_JOIN_SESSION, 1, 400, updates)->status, Status::NotFound);
}
