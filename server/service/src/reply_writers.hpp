// One reply writer per client, in the client's own partition ("surfeledit.reply.<client id>"), so
// that a client's replies reach only readers in that partition: its own, unless another participant
// subscribes to it on purpose (partitions are visible in discovery; PROTOCOL.md, "Identity and
// access"). A writer is made when a client's first reply is written and keeps its last replies
// (transient-local, depth kReplyDepth), so the reply reaches the client's reader even when that
// reader matches the new writer only after the write. Private to the service library.
#pragma once

#include <map>
#include <string>

#include "dds_handles.hpp"

namespace surfeledit::service {

// The partition of a client's replies (the Python client subscribes its reply reader to it).
std::string reply_partition(const std::string& client_id);

class ReplyWriters {
 public:
  // `liveliness`: the automatic liveliness lease every reply writer offers.
  ReplyWriters(const dds::Entity& participant, const dds::Entity& topic, dds_duration_t liveliness);
  // The client's writer, made on first use.
  const dds::Entity& for_client(const std::string& client_id);
  // Deletes the client's writer (it was detached).
  void drop(const std::string& client_id);
  std::size_t size() const { return writers_.size(); }

 private:
  struct ClientWriter {
    dds::Entity publisher;  // in the client's partition; owns the writer
    dds::Entity writer;
  };
  const dds::Entity& participant_;
  const dds::Entity& topic_;
  dds_duration_t liveliness_;
  std::map<std::string, ClientWriter> writers_;
};

}  // namespace surfeledit::service
