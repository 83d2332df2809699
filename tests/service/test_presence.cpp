// Collaboration in the handler (issue 11 §2, §4): expect_version, OP_PEERS, presence updates and their
// authors, and the grace period of a session whose last client was detached by its lease.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "handler_fixture.hpp"
#include "surfeledit/service/sample_views.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;
using namespace std::chrono_literals;

namespace {

class Collaboration : public HandlerTest {
 protected:
  std::vector<std::uint64_t> zero_ids, one_ids, expected;

  // A request of the builder's client from writer `sender` (0: unbound), optionally with expect_version.
  std::shared_ptr<const Reply> send_as(surfeledit_proto_Op op, std::uint64_t sender,
                                       std::vector<std::uint64_t> expect = {}) {
    expected = std::move(expect);
    surfeledit_proto_Request req = rb.make(op, next_id++);
    point_to(req.expect_version, expected);
    Command c = decode(req);
    c.sender = sender;
    return handler.handle(c, updates);
  }

  // Zero region: ids 0..9, one region: ids n-10..n-1 of a loaded model of n surfels.
  void regions(std::size_t n) {
    zero_ids.clear();
    one_ids.clear();
    for (std::uint64_t id = 0; id < 10; ++id) zero_ids.push_back(id);
    for (std::uint64_t id = n - 10; id < n; ++id) one_ids.push_back(id);
    rb.set_regions = surfeledit_proto_SetRegions{};
    point_to(rb.set_regions.zero.ids, zero_ids);
    point_to(rb.set_regions.one.ids, one_ids);
  }

  std::uint64_t history_size() {
    return send_as(surfeledit_proto_OP_HISTORY, 0)->history.size();
  }
};

}  // namespace

TEST_F(Collaboration, ExpectVersionRefusesAStaleOpAndChangesNothing) {
  load(40);
  regions(40);
  auto r = send_as(surfeledit_proto_OP_SET_REGIONS, 0, {1});  // the session is at version 1: runs
  ASSERT_EQ(r->status, Status::Ok) << r->message;
  ASSERT_EQ(r->version, 2u);
  const std::uint64_t entries = history_size();
  updates.clear();
  r = send_as(surfeledit_proto_OP_SET_REGIONS, 0, {1});  // another op came first
  EXPECT_EQ(r->status, Status::Conflict);
  EXPECT_EQ(r->field, "expect_version");
  EXPECT_NE(r->message.find("it is at version 2"), std::string::npos) << r->message;
  EXPECT_EQ(r->version, 2u);
  EXPECT_TRUE(updates.empty());
  EXPECT_EQ(history_size(), entries);
  r = send_as(surfeledit_proto_OP_DEFORM, 0, {9});  // never reached
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "expect_version");
  r = send_as(surfeledit_proto_OP_SET_REGIONS, 0, {2, 2});  // one element at most
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "expect_version");
  EXPECT_EQ(send_as(surfeledit_proto_OP_GET_STATE, 0, {0})->status, Status::Ok);  // reads ignore it
  EXPECT_EQ(send_as(surfeledit_proto_OP_DEFORM, 0, {2})->version, 3u);
  EXPECT_EQ(history_size(), entries + 1);
}

TEST_F(Collaboration, PeersAndPresenceNameTheClientsTheirRolesLastOpsAndTools) {
  load(40);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "load");
  EXPECT_EQ(updates[0].author, "client-a");
  rb.token = send_as(surfeledit_proto_OP_INVITE, 0)->token;
  rb.client = "client-b";
  updates.clear();
  ASSERT_EQ(send_as(surfeledit_proto_OP_JOIN_SESSION, 0)->status, Status::Ok);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "presence");
  EXPECT_EQ(updates[0].presence, "join");
  EXPECT_EQ(updates[0].author, "client-b");
  ASSERT_EQ(updates[0].peers.size(), 2u);
  regions(40);
  updates.clear();
  const auto set = send_as(surfeledit_proto_OP_SET_REGIONS, 0);
  ASSERT_EQ(set->status, Status::Ok) << set->message;
  ASSERT_EQ(updates.size(), 2u);
  EXPECT_EQ(updates[0].cause, "regions");
  EXPECT_EQ(updates[0].author, "client-b");
  EXPECT_EQ(updates[1].presence, "regions");
  rb.client = "client-a";
  const auto peers = send_as(surfeledit_proto_OP_PEERS, 0);
  ASSERT_EQ(peers->status, Status::Ok);
  ASSERT_EQ(peers->peers.size(), 2u);
  const PeerInfo& a = peers->peers[0];
  const PeerInfo& b = peers->peers[1];
  EXPECT_EQ(a.client_id, "client-a");
  EXPECT_EQ(a.role, "owner");
  EXPECT_EQ(a.last_op, "load_commit");
  EXPECT_EQ(a.last_version, 1u);
  EXPECT_EQ(b.client_id, "client-b");
  EXPECT_EQ(b.role, "editor");
  EXPECT_EQ(b.state, "attached");
  EXPECT_EQ(b.last_op, "set_regions");
  EXPECT_EQ(b.last_version, set->version);
  // Tools are per client: b's holds the regions it set, a has none.
  EXPECT_EQ(b.zero, zero_ids.size());
  EXPECT_EQ(b.one, one_ids.size());
  EXPECT_EQ(b.deformable, 40u - zero_ids.size());  // every surfel outside the zero region moves
  EXPECT_EQ(a.zero + a.one + a.deformable, 0u);
  rb.client = "client-b";
  updates.clear();
  ASSERT_EQ(send_as(surfeledit_proto_OP_CLOSE_SESSION, 0)->status, Status::Ok);
  ASSERT_EQ(updates.size(), 2u);  // leaving releases b's tool (one history entry), then the presence change
  EXPECT_EQ(updates[0].cause, "release");
  EXPECT_EQ(updates[0].author, "client-b");
  EXPECT_EQ(updates[1].presence, "leave");
  ASSERT_EQ(updates[1].peers.size(), 1u);
  EXPECT_EQ(updates[1].peers[0].client_id, "client-a");
}

TEST(CollaborationGrace, ASessionLeftByALeaseIsKeptForTheGracePeriodThenDropped) {
  LeasedHandler lh(1ms, 200ms);
  ASSERT_EQ(lh.send_from(surfeledit_proto_OP_OPEN_SESSION, 100)->status, Status::Ok);
  lh.handler.writer_lost(100);
  std::this_thread::sleep_for(5ms);
  lh.updates.clear();
  ASSERT_EQ(lh.handler.expire_leases(lh.updates), std::vector<std::string>{"client-a"});
  ASSERT_EQ(lh.updates.size(), 1u);
  EXPECT_EQ(lh.updates[0].presence, "expired");
  ASSERT_EQ(lh.updates[0].peers.size(), 1u);
  EXPECT_EQ(lh.updates[0].peers[0].state, "away");
  // The loop wakes for the grace deadline.
  ASSERT_TRUE(lh.handler.next_lease_check());
  EXPECT_LE(*lh.handler.next_lease_check(), 200ms);
  EXPECT_GT(*lh.handler.next_lease_check(), 100ms);
  // A restarted client (another writer, same id) joins as a member, without a token: its role survived.
  lh.updates.clear();
  const auto back = lh.send_from(surfeledit_proto_OP_JOIN_SESSION, 200);
  ASSERT_EQ(back->status, Status::Ok) << back->message;
  ASSERT_EQ(lh.updates.size(), 1u);
  EXPECT_EQ(lh.updates[0].presence, "join");
  EXPECT_EQ(lh.updates[0].peers[0].role, "owner");
  EXPECT_EQ(lh.updates[0].peers[0].state, "attached");
  EXPECT_FALSE(lh.handler.next_lease_check());  // nothing runs: the session has a client again
  // Gone again, and nobody comes back: dropped after the grace period with a "close" update.
  lh.handler.writer_lost(200);
  std::this_thread::sleep_for(5ms);
  lh.updates.clear();
  lh.handler.expire_leases(lh.updates);
  ASSERT_EQ(lh.updates.size(), 1u);
  std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(lh.handler.expire_leases(lh.updates).empty());
  EXPECT_EQ(lh.updates.size(), 1u);  // still within the grace period
  std::this_thread::sleep_for(*lh.handler.next_lease_check() + 2ms);
  lh.handler.expire_leases(lh.updates);
  ASSERT_EQ(lh.updates.size(), 2u);
  EXPECT_EQ(lh.updates[1].cause, "close");
  EXPECT_EQ(lh.updates[1].author, "");
  EXPECT_EQ(lh.send_from(surfeledit_proto_OP_JOIN_SESSION, 300)->status, Status::NotFound);
  EXPECT_FALSE(lh.handler.next_lease_check());
}

TEST(CollaborationWire, PeersAndAuthorsReachTheSamples) {
  Reply r;
  r.peers.push_back(PeerInfo{"a", "owner", "attached", "deform", 7, 12.5, 10, 20, 30});
  r.peers.push_back(PeerInfo{"b", "viewer", "away", "", 0, 1.0, 0, 0, 0});
  const ReplyView view(r);
  ASSERT_EQ(view.get()->peers._length, 2u);
  const surfeledit_proto_Peer& a = view.get()->peers._buffer[0];
  EXPECT_STREQ(a.client_id, "a");
  EXPECT_STREQ(a.role, "owner");
  EXPECT_STREQ(a.state, "attached");
  EXPECT_STREQ(a.last_op, "deform");
  EXPECT_EQ(a.last_version, 7u);
  EXPECT_EQ(a.idle_ms, 12.5);
  EXPECT_EQ(a.zero, 10u);
  EXPECT_EQ(a.one, 20u);
  EXPECT_EQ(a.deformable, 30u);
  EXPECT_STREQ(view.get()->peers._buffer[1].state, "away");

  // An update of 3 surfels in parts of 2: the author and presence in every part, the peers in part 0.
  UpdateEvent event = make_update_event("s", 4, "presence");
  event.author = "a";
  event.presence = "join";
  event.peers = r.peers;
  PreparedUpdate update = prepare_update(event, nullptr);
  update.ids = {1, 2, 3};
  update.positions.assign(9, 0.0);
  update.normals.assign(9, 0.0);
  update.radii.assign(3, 1.0);
  ASSERT_EQ(update_parts(update, 2), 2u);
  const UpdateView first(update_chunk(update, 0, 2));
  const UpdateView second(update_chunk(update, 1, 2));
  EXPECT_STREQ(first.get()->author, "a");
  EXPECT_STREQ(second.get()->author, "a");
  EXPECT_STREQ(first.get()->presence, "join");
  EXPECT_STREQ(second.get()->presence, "join");
  EXPECT_EQ(first.get()->peers._length, 2u);
  EXPECT_EQ(second.get()->peers._length, 0u);
}

TEST(CollaborationGrace, TheLastCloseKeepsASessionWhileAMemberIsAway) {
  LeasedHandler lh(1ms, 10s);
  ASSERT_EQ(lh.send_from(surfeledit_proto_OP_OPEN_SESSION, 100)->status, Status::Ok);
  lh.rb.token = lh.send_from(surfeledit_proto_OP_INVITE, 100)->token;
  lh.rb.client = "client-b";
  ASSERT_EQ(lh.send_from(surfeledit_proto_OP_JOIN_SESSION, 300)->status, Status::Ok);
  lh.rb.token.clear();
  lh.handler.writer_lost(300);
  std::this_thread::sleep_for(5ms);
  ASSERT_EQ(lh.handler.expire_leases(lh.updates), std::vector<std::string>{"client-b"});
  lh.rb.client = "client-a";
  lh.updates.clear();
  ASSERT_EQ(lh.send_from(surfeledit_proto_OP_CLOSE_SESSION, 100)->status, Status::Ok);
  ASSERT_EQ(lh.updates.size(), 1u);  // no "close": client-b may come back
  EXPECT_EQ(lh.updates[0].presence, "leave");
  lh.rb.client = "client-b";
  const auto back = lh.send_from(surfeledit_proto_OP_JOIN_SESSION, 400);
  ASSERT_EQ(back->status, Status::Ok) << back->message;
  EXPECT_EQ(back->session_info->clients, 1u);
}
