// One reply writer per client, in the client's own partition ("surfeledit.reply.<client id>"), so
// that a client's replies reach only readers in that partition: its own, unless another participant
// subscribes to it on purpose (partitions are visible in discovery; PROTOCOL.md, "Identity and
// access"). A writer is made when a client's first reply is written and keeps its last replies
// (transient-local, depth kReplyDepth), so the reply reaches the client's reader even when that
// reader matches the new writer only after the write. Private to the service library.
//
// Deleting the writer of a client that died blocks: Cyclone keeps a reliable writer with
// unacknowledged samples "lingering" until they are acknowledged or its WriterLingerDuration (1 s by
// default) passes, and dds_delete waits for that. The dead client's reader never acknowledges (it
// is still matched until discovery's own participant lease, 10 s by default, runs out), so a dropped
// writer is deleted on a thread of its own (the deleter), never on the request thread.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "dds_handles.hpp"

namespace surfeledit::service {

// The partition of a client's replies (the Python client subscribes its reply reader to it).
std::string reply_partition(const std::string& client_id);

class ReplyWriters {
 public:
  // `liveliness`: the automatic liveliness lease every reply writer offers. `participant` and
  // `topic` must outlive this object.
  ReplyWriters(const dds::Entity& participant, const dds::Entity& topic, dds_duration_t liveliness);
  // Deletes the writers still queued for deletion and the current ones (may block up to Cyclone's
  // linger duration per writer of a dead client), then joins the deleter.
  ~ReplyWriters();
  ReplyWriters(const ReplyWriters&) = delete;
  ReplyWriters& operator=(const ReplyWriters&) = delete;

  // The client's writer, made on first use.
  const dds::Entity& for_client(const std::string& client_id);
  // Forgets the client's writer (it was detached) and hands it to the deleter: returns at once.
  void drop(const std::string& client_id);
  std::size_t size() const { return writers_.size(); }
  // Writers dropped and not yet deleted (a test and log figure).
  std::size_t retiring() const;

 private:
  struct ClientWriter {
    dds::Entity publisher;  // in the client's partition; owns the writer
    dds::Entity writer;
  };
  void delete_retired();  // the deleter thread's loop

  const dds::Entity& participant_;
  const dds::Entity& topic_;
  dds_duration_t liveliness_;
  std::map<std::string, ClientWriter> writers_;  // request thread only

  mutable std::mutex mutex_;               // guards retired_, stopping_
  std::condition_variable wake_;           // a writer was retired, or stopping
  std::deque<ClientWriter> retired_;       // dropped writers waiting for the deleter
  bool stopping_ = false;
  std::thread deleter_;                    // last: started once the members above exist
};

}  // namespace surfeledit::service
