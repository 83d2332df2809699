// Writes prepared updates on a thread of its own, in the order they were queued, so that the
// request loop never waits for the (large) Update samples to be serialised and sent.
//
// The queue is bounded by payload bytes. push() never blocks: when an update does not fit, it
// is refused and the caller decides (the service coalesces the session's queued updates into one,
// see service_updates.cpp). push_anyway() accepts an update beyond the bound (used for the coalesced
// update and when nothing can be coalesced; logged by the caller). No DDS here: the writer is a
// callback, so the queue is testable on its own.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "surfeledit/service/update.hpp"

namespace surfeledit::service {

class UpdatePublisher {
 public:
  // Writes every sample of one update; may throw (the publisher logs and goes on).
  using Writer = std::function<void(const PreparedUpdate&)>;

  struct Counters {
    std::uint64_t queued = 0;       // updates accepted (push or push_anyway)
    std::uint64_t published = 0;    // written without error
    std::uint64_t failed = 0;       // the writer threw
    std::uint64_t taken_back = 0;   // removed by take_pending (e.g. coalesced by the caller)
    std::uint64_t dropped = 0;      // still queued when shutdown's drain deadline passed
    std::size_t max_queued_bytes = 0;  // high-water mark of queued payload
  };

  // Starts the thread. `max_queued_bytes` > 0 bounds the payload held by queued (not yet written) updates.
  UpdatePublisher(Writer writer, std::size_t max_queued_bytes);
  // shutdown() with the default deadline.
  ~UpdatePublisher();
  UpdatePublisher(const UpdatePublisher&) = delete;
  UpdatePublisher& operator=(const UpdatePublisher&) = delete;

  // Queues `update` unless it would take the queued payload beyond the bound (an update is always
  // accepted into an empty queue). Returns false (and leaves `update` untouched) when refused or
  // after shutdown.
  bool push(PreparedUpdate& update);
  // Queues `update` even beyond the bound; false only after shutdown.
  bool push_anyway(PreparedUpdate&& update);
  // Removes the queued (not yet started) updates of `session` if they are exactly the versions
  // first..last with last + 1 == `next_version`, each with a cause in `incremental` (e.g.
  // "deform", "remove", "regions"); returns them oldest first, or nothing (the queue unchanged).
  std::vector<PreparedUpdate> take_pending(const std::string& session, std::uint64_t next_version,
                                           const std::vector<std::string>& incremental);

  // Stops accepting updates, writes what is queued until `drain_deadline` has passed, drops the
  // rest, and joins the thread. Idempotent. Returns the counters (dropped: what was not written).
  Counters shutdown(std::chrono::milliseconds drain_deadline = std::chrono::milliseconds(2000));

  Counters counters() const;
  std::size_t queued_bytes() const;
  std::size_t queued_updates() const;
  std::size_t max_queued_bytes() const { return max_bytes_; }
  // Blocks until everything queued so far has been written (for tests and benchmarks).
  void wait_idle() const;

 private:
  // push() (bounded) and push_anyway(): queues `update` (moved from) unless stopping or, when
  // `bounded`, beyond the byte bound of a non-empty queue.
  bool enqueue(PreparedUpdate& update, bool bounded);
  void run();

  Writer writer_;
  const std::size_t max_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;          // work queued or shutting down
  mutable std::condition_variable idle_;  // the queue became empty and nothing is being written
  std::deque<PreparedUpdate> queue_;
  std::size_t bytes_ = 0;                 // payload of queue_
  bool busy_ = false;                     // the thread is writing an update
  bool stopping_ = false;
  std::chrono::steady_clock::time_point drain_until_{};
  Counters counters_;
  std::thread thread_;  // last: started after everything it uses is initialised
};

}  // namespace surfeledit::service
