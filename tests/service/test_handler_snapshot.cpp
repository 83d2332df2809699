// Handler::save / snapshot / restore (the service state of a journal snapshot): a restored handler answers
// repeated request ids with the replies first sent (their CDR), serves the same session state and roles,
// and a truncated or corrupt snapshot changes nothing; an unfinished upload defers the save; a snapshot
// encoded after the state changed writes the state of its point.
#include <gtest/gtest.h>

#include <string>

#include "../../server/service/src/journal_records.hpp"
#include "handler_fixture.hpp"
#include "surfeledit/core/snapshot_io.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

namespace {

std::shared_ptr<const Reply> send_to(Handler& h, RequestBuilder& rb, surfeledit_proto_Op op, std::uint64_t id,
                                     std::vector<UpdateEvent>& updates) {
  return h.handle(decode(rb.make(op, id)), updates);
}

}  // namespace

TEST_F(HandlerTest, SnapshotRestoresSessionsRolesAndStoredRepliesAndACorruptOneChangesNothing) {
  load(8);
  const std::uint64_t invite_id = next_id;
  rb.role = "viewer";
  const auto invited = send(surfeledit_proto_OP_INVITE);
  ASSERT_EQ(invited->status, Status::Ok);
  const std::uint64_t refused_id = next_id;
  const auto refused = send(surfeledit_proto_OP_LOAD_COMMIT);  // no upload: Conflict, stored for repeats
  ASSERT_EQ(refused->status, Status::Conflict);
  const auto info = send(surfeledit_proto_OP_INFO);
  ASSERT_TRUE(info->session_info);
  ASSERT_TRUE(handler.not_snapshottable().why.empty()) << handler.not_snapshottable().why;

  std::vector<std::string> parts;
  handler.save(parts);
  std::string bytes;
  for (const std::string& part : parts) bytes += part;

  // Truncated or corrupt: refused, and a handler that had nothing still has nothing.
  Handler other{HandlerConfig{4, 1000, 1}};
  for (std::size_t cut : {std::size_t(0), std::size_t(7), bytes.size() / 3, bytes.size() - 1}) {
    SnapshotReader in(bytes.data(), cut);
    EXPECT_THROW(other.restore(in), Error) << cut;
  }
  std::string flipped = bytes;
  flipped[4] ^= 0x40;  // the service format
  SnapshotReader bad(flipped);
  EXPECT_THROW(other.restore(bad), Error);
  EXPECT_EQ(send_to(other, rb, surfeledit_proto_OP_INFO, 9000, updates)->session_info, std::nullopt);

  SnapshotReader in(bytes);
  Handler restored{HandlerConfig{4, 1000, 1}};
  restored.restore(in);
  // Repeats get the stored replies, as first sent (the CDR of the IDL Reply), and change nothing.
  const auto invited_again = send_to(restored, rb, surfeledit_proto_OP_INVITE, invite_id, updates);
  EXPECT_FALSE(invited_again->wire.empty());
  EXPECT_EQ(invited_again->token, invited->token);
  const journal::ReplySample sample(invited_again->wire);
  EXPECT_STREQ(sample.get().token, invited->token.c_str());
  EXPECT_EQ(sample.get().request_id, invite_id);
  const auto refused_again = send_to(restored, rb, surfeledit_proto_OP_LOAD_COMMIT, refused_id, updates);
  EXPECT_EQ(refused_again->status, Status::Conflict);
  EXPECT_EQ(refused_again->message, refused->message);
  EXPECT_EQ(refused_again->version, refused->version);
  // The same session: version and state hash; the invitation admits another client as a viewer.
  const auto info_after = send_to(restored, rb, surfeledit_proto_OP_INFO, 9001, updates);
  ASSERT_TRUE(info_after->session_info);
  EXPECT_EQ(info_after->version, info->version);
  EXPECT_EQ(info_after->session_info->state_hash, info->session_info->state_hash);
  RequestBuilder guest;
  guest.client = "client-b";
  guest.token = invited->token;
  EXPECT_EQ(send_to(restored, guest, surfeledit_proto_OP_JOIN_SESSION, 1, updates)->status, Status::Ok);
  EXPECT_EQ(send_to(restored, guest, surfeledit_proto_OP_LOAD_BEGIN, 2, updates)->status, Status::PermissionDenied);
  // A corrupt snapshot leaves a restored handler as it was too.
  SnapshotReader bad_again(flipped);
  EXPECT_THROW(restored.restore(bad_again), Error);
  EXPECT_EQ(send_to(restored, rb, surfeledit_proto_OP_INFO, 9002, updates)->session_info->state_hash,
            info->session_info->state_hash);

  // An unfinished upload defers the save (it ends by itself: `soon`).
  rb.load_begin.total = 4;
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
  EXPECT_TRUE(handler.not_snapshottable().soon);
  std::vector<std::string> refused_parts;
  EXPECT_THROW(handler.save(refused_parts), Error);
}

// Handler::snapshot (the journal's writer thread encodes it): taken at one point and encoded after the
// session changed (a second upload replaces the model and pushes a history entry), its parts concatenate
// to the bytes save() gave at that point. Truth: that save.
TEST_F(HandlerTest, SnapshotEncodedLaterWritesThePoint) {
  load(8);
  std::vector<std::string> at_point;
  handler.save(at_point);
  const Handler::Snapshot snap = handler.snapshot();
  EXPECT_GT(snap.shared_images(), 0u);
  EXPECT_GT(snap.copied_bytes(), 0u);
  const auto info = send(surfeledit_proto_OP_INFO);
  // A second upload of another size: a new model, a new history entry.
  const std::size_t n = 12;
  rb.load_begin.total = n;
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
  for (std::size_t first = 0; first < n; first += 4) {
    ChunkArrays c = sphere_chunk(4, first, n);
    rb.load_chunk.offset = first;
    point_to(rb.load_chunk.positions, c.positions);
    point_to(rb.load_chunk.normals, c.normals);
    point_to(rb.load_chunk.radii, c.radii);
    ASSERT_EQ(send(surfeledit_proto_OP_LOAD_CHUNK)->status, Status::Ok);
  }
  ASSERT_EQ(send(surfeledit_proto_OP_LOAD_COMMIT)->status, Status::Ok);
  std::vector<std::string> now;
  handler.save(now);
  std::vector<std::string> later;
  snap.encode(later);
  // Parts: the service's bytes with the session's size, the session's core snapshot, the rest. The service's
  // bytes hold ages (now minus each client's last request), which differ by the time between the two calls;
  // the session's bytes must be equal.
  ASSERT_EQ(at_point.size(), 3u);
  ASSERT_EQ(later.size(), 3u);
  EXPECT_EQ(at_point[0].size(), later[0].size());
  EXPECT_TRUE(at_point[1] == later[1]) << at_point[1].size() << " / " << later[1].size();
  EXPECT_EQ(at_point[2].size(), later[2].size());
  EXPECT_FALSE(now[1] == at_point[1]);  // the session did change after the point
  std::string b;
  for (const std::string& p : later) b += p;
  // Restored, it is the session as it was at the point.
  SnapshotReader in(b);
  Handler restored{HandlerConfig{4, 1000, 1}};
  restored.restore(in);
  const auto info_after = send_to(restored, rb, surfeledit_proto_OP_INFO, 9000, updates);
  ASSERT_TRUE(info_after->session_info);
  EXPECT_EQ(info_after->version, info->version);
  EXPECT_EQ(info_after->session_info->state_hash, info->session_info->state_hash);
}
