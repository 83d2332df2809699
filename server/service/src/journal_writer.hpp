// The journal's writer thread (docs/journal.md "Snapshots: the writer thread"): encodes a snapshot
// taken at its point (Handler::Snapshot) and writes its file off the request thread (temporary name, fdatasync, rename, directory fsync) and deletes the
// files a durable snapshot made obsolete. One thread, one queue of jobs done in order; at most one
// snapshot in flight (the journal checks busy() before it hands one over). The request thread owns the
// log: it appends the Snapshot record once this thread reports the file durable. Private to the service.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "journal_records.hpp"
#include "journal_snapshot.hpp"
#include "surfeledit/service/journal.hpp"

namespace surfeledit::service::journal {

// A snapshot file the thread finished (or failed to write).
struct WrittenSnapshot {
  std::uint64_t seq = 0;    // its number
  SnapshotRecord record;    // its record (records = 0: the journal fills it in); valid when error is empty
  std::string error;        // why it was not written (what it wrote is removed)
  SnapshotFileTimes times;  // where the thread's time went (after encoding)
  double encode_ms = 0.0;   // encoding it (Handler::Snapshot::encode), before the file was written
};

class SnapshotThread {
 public:
  // Opens `dir` (its fsyncs are this thread's) and starts the thread. `on_written` is called on the
  // thread after each snapshot job, written or not (it must be thread-safe: it wakes the request loop).
  // Throws JournalError.
  SnapshotThread(std::string dir, std::function<void()> on_written);
  // Finishes the jobs queued (a snapshot in hand is written to its end) and joins the thread.
  ~SnapshotThread();
  SnapshotThread(const SnapshotThread&) = delete;
  SnapshotThread& operator=(const SnapshotThread&) = delete;

  // Hands snapshot `seq` over, its payload (the concatenation of parts) made on this thread by `encode`
  // (which appends the parts; destroyed on this thread once it ran). A throw from it is the snapshot's
  // failure, like a failed write. Requires !busy().
  using Encoder = std::function<void(std::vector<std::string>& parts)>;
  void write(std::uint64_t seq, Encoder encode);
  // The same with the parts ready.
  void write(std::uint64_t seq, std::vector<std::string> parts);
  // Hands over files to delete in order (journal segments), then the snapshots below `seq` and every
  // temporary one, then a directory fsync. A failure is logged (the files stay; nothing depends on them).
  void remove(std::vector<std::string> segments, std::uint64_t snapshots_before);
  // Hands over creating segment `segment` ahead (JournalLog::create_segment), for the next snapshot's point.
  void prepare(std::uint64_t segment);
  // The segment the last prepare() created (0: none, or it failed; it is logged).
  std::uint64_t prepared() const;
  // A snapshot was handed over and its result not taken yet.
  bool busy() const;
  // The result of the snapshot handed over, once the thread finished it (nullopt: none, or not yet).
  std::optional<WrittenSnapshot> take_written();
  // Waits until every job handed over is done (the snapshot in hand written or failed).
  void wait_idle();

 private:
  enum class Kind { Write, Remove, Prepare };
  struct Job {
    Kind kind = Kind::Write;
    std::uint64_t seq = 0;  // write: the snapshot's number; remove: snapshots below it; prepare: the segment
    Encoder encode;                         // write: makes the payload
    std::vector<std::string> parts;         // write: the payload, once made (on this thread)
    std::vector<std::string> segments;      // remove: segment files, oldest first
  };
  void push(Job job);
  void run();
  void remove_files(const Job& job);

  std::string dir_;
  UniqueFd dir_fd_;
  std::function<void()> on_written_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;             // a job was queued, or stop
  std::condition_variable idle_;             // the queue ran empty
  std::deque<Job> jobs_;                     // guarded by mutex_
  bool working_ = false;                     // a job is being done (guarded)
  bool stop_ = false;                        // guarded
  bool in_flight_ = false;                   // a snapshot was handed over, its result not taken (guarded)
  std::optional<WrittenSnapshot> written_;   // guarded
  std::uint64_t prepared_ = 0;               // the segment created ahead (guarded)
  std::thread thread_;                       // last: started once the rest is ready
};

}  // namespace surfeledit::service::journal
