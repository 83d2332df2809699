// The request handler driven with generated C requests, decoded as the service decodes them.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "service_test_support.hpp"
#include "surfeledit/service/decode.hpp"
#include "surfeledit/service/handler.hpp"

namespace surfeledit::service::test {

class HandlerTest : public ::testing::Test {
 protected:
  Handler handler{HandlerConfig{4, 1000, 1}};
  RequestBuilder rb;
  std::vector<UpdateEvent> updates;
  std::uint64_t next_id = 1;

  std::shared_ptr<const Reply> send(surfeledit_proto_Op op, std::uint64_t id = 0) {
    return handler.handle(decode(rb.make(op, id ? id : next_id++)), updates);
  }

  // Opens session "s" and uploads n sphere surfels in chunks of 4.
  void load(std::size_t n) {
    ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
    updates.clear();  // the presence update of the open
    rb.load_begin.total = n;
    rb.load_begin.has_radii = true;
    ASSERT_EQ(send(surfeledit_proto_OP_LOAD_BEGIN)->status, Status::Ok);
    for (std::size_t first = 0; first < n; first += 4) {
      ChunkArrays c = sphere_chunk(std::min<std::size_t>(4, n - first), first, n);
      rb.load_chunk.offset = first;
      point_to(rb.load_chunk.positions, c.positions);
      point_to(rb.load_chunk.normals, c.normals);
      point_to(rb.load_chunk.radii, c.radii);
      const auto r = send(surfeledit_proto_OP_LOAD_CHUNK);
      ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
    }
    const auto r = send(surfeledit_proto_OP_LOAD_COMMIT);
    ASSERT_EQ(r->status, Status::Ok) << r->field << ": " << r->message;
  }
};

// A handler with the given lease and grace period, driven by requests from several DDS writers
// (`sender`: the publication handle the service would see for the request's writer).
struct LeasedHandler {
  static HandlerConfig config(std::chrono::milliseconds lease, std::chrono::milliseconds grace) {
    HandlerConfig c{4, 1000, 1};
    c.client_lease = lease;
    c.session_grace = grace;
    return c;
  }

  LeasedHandler(std::chrono::milliseconds lease, std::chrono::milliseconds grace) : handler(config(lease, grace)) {}

  // The builder's request `op` from writer `sender`, with request id `id` (0: the next one).
  std::shared_ptr<const Reply> send_from(surfeledit_proto_Op op, std::uint64_t sender, std::uint64_t id = 0) {
    Command c = decode(rb.make(op, id ? id : next_id++));
    c.sender = sender;
    return handler.handle(c, updates);
  }

  Handler handler;
  RequestBuilder rb;
  std::vector<UpdateEvent> updates;
  std::uint64_t next_id = 1;
};

}  // namespace surfeledit::service::test
