// Journal snapshots taken between two requests and handed to the writer thread (docs/journal.md
// "Snapshots: the writer thread"): when one is due, the point on the request loop, and the record once the
// writer thread made the file durable. Recovery from a snapshot is in journal.cpp.
#include <algorithm>

#include "journal.hpp"
#include "journal_records.hpp"
#include "surfeledit/service/log.hpp"

namespace surfeledit::service {

namespace {

constexpr std::uint64_t kRetryRecords = 8;  // a deferred or failed snapshot is tried again after this many records

}  // namespace

void Journal::start_writer() {
  if (writer_) return;
  writer_ = std::make_unique<journal::SnapshotThread>(config_.dir, [this] {
    if (on_written_) on_written_();
  });
}

Journal::~Journal() {
  writer_.reset();  // finishes its jobs (a snapshot in hand is written; without its record it is ignored)
}

void Journal::maybe_snapshot() {
  if (writer_ && in_flight_) {
    if (auto written = writer_->take_written()) complete_snapshot(*written);
  }
  if (failed() || (config_.snapshot_records == 0 && config_.snapshot_mb == 0)) return;
  const bool due = (config_.snapshot_records && since_snapshot_ >= config_.snapshot_records) ||
                   (config_.snapshot_mb && log_->segment_bytes() > (config_.snapshot_mb << 20));
  // At most one in flight: a due snapshot waits for the writer thread (tried again when it finished).
  if (!due || since_snapshot_ < retry_at_ || in_flight_) return;
  const Handler::SnapshotBlock block = handler_.not_snapshottable();
  if (!block.why.empty()) {
    // Tried again at the next record when an upload or load is what waits (it ends by itself), else a
    // few records later (a session that is not snapshottable is closed or reconfigured).
    retry_at_ = since_snapshot_ + (block.soon ? 1 : kRetryRecords);
    if (block.why != deferred_) {
      logger()->info("journal: snapshot deferred ({}); the log keeps every record", block.why);
    }
    deferred_ = block.why;
    return;
  }
  deferred_.clear();
  retry_at_ = 0;
  take_snapshot();
}

void Journal::take_snapshot() {
  const auto t0 = Clock::now();
  flush(true);  // the open group's records are durable and its replies out: the new segment's syncs miss them
  if (failed()) return;
  const std::uint64_t seq = log_->segment() + 1;
  InFlight taken;
  taken.taken = t0;
  taken.records = total_records_;
  auto snapshot = std::make_shared<Handler::Snapshot>();
  try {
    start_writer();
    const auto s0 = Clock::now();
    // The state at this point, encoded by the writer thread while requests go on (the history's images
    // shared, the rest copied here).
    *snapshot = handler_.snapshot();
    const auto s1 = Clock::now();
    taken.save_ms = std::chrono::duration<double, std::milli>(s1 - s0).count();
    // Every later record goes to segment `seq`: the state saved is its start. Its file was created ahead by
    // the writer thread, unless that is still under way (waited for) or failed (created here).
    if (writer_->prepared() != seq) writer_->wait_idle();
    log_->start_segment(seq, writer_->prepared() == seq);
    taken.segment_ms = std::chrono::duration<double, std::milli>(Clock::now() - s1).count();
  } catch (const std::exception& e) {
    // Nothing changed: the log goes on in its segment; tried again after as many records.
    retry_at_ = since_snapshot_ + std::max<std::uint64_t>(config_.snapshot_records, kRetryRecords);
    logger()->error("journal: snapshot {} not taken: {}; the log keeps every record", seq, e.what());
    return;
  }
  since_snapshot_ = 0;
  const std::size_t copied = snapshot->copied_bytes(), shared = snapshot->shared_images();
  writer_->write(seq, [snapshot](std::vector<std::string>& parts) { snapshot->encode(parts); });
  snapshot.reset();  // the writer thread's alone now: it lets go of the images it shares
  taken.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  in_flight_ = taken;
  logger()->info("journal: snapshot {} started after {} record(s): the request loop waited {:.1f} ms, of which "
                 "{:.1f} ms saving the state and {:.1f} ms starting its segment; the writer thread encodes and "
                 "writes it ({:.2f} MB copied at its point, {} history image(s) shared)",
                 seq, taken.records, taken.ms, taken.save_ms, taken.segment_ms, static_cast<double>(copied) / 1e6,
                 shared);
}

void Journal::complete_snapshot(const journal::WrittenSnapshot& written) {
  const InFlight taken = *in_flight_;
  in_flight_.reset();
  if (failed()) return;  // nothing more is journaled; the file without its record is never used
  if (!written.error.empty()) {
    // Its segment stays without a record: recovery replays it from the snapshot before (or the log's start).
    retry_at_ = since_snapshot_ + std::max<std::uint64_t>(config_.snapshot_records, kRetryRecords);
    logger()->error("journal: snapshot {} not written: {}; the log keeps every record", written.seq, written.error);
    writer_->prepare(log_->segment() + 1);
    return;
  }
  journal::SnapshotRecord record = written.record;
  record.records = taken.records;
  try {
    append(RecordKind::Snapshot, journal::encode(record));
  } catch (const std::exception& e) {
    failure_ = std::string("journal: ") + e.what();
    logger()->critical("{}: no more replies are sent", failure_);
    return;
  }
  flush(true);  // the record durable (and the open group's replies out) before older files go
  if (failed()) return;
  // The new snapshot is durable: keep the one before it as its fallback, drop what is older.
  writer_->remove(log_->forget_segments_before(kept_snapshot_), kept_snapshot_);
  writer_->prepare(log_->segment() + 1);
  kept_snapshot_ = written.seq;
  snapshots_.taken += 1;
  snapshots_.seq = written.seq;
  snapshots_.bytes = record.file_bytes;
  snapshots_.ms = taken.ms;
  snapshots_.save_ms = taken.save_ms;
  snapshots_.encode_ms = written.encode_ms;
  snapshots_.write_ms = written.times.write_ms;
  snapshots_.sync_ms = written.times.sync_ms;
  snapshots_.total_ms = std::chrono::duration<double, std::milli>(Clock::now() - taken.taken).count();
  logger()->info("journal: snapshot {} taken after {} record(s): {:.2f} MB, the request loop waited {:.1f} ms, of "
                 "which {:.1f} ms saving the state; the writer thread wrote it in {:.1f} ms and synced it in {:.1f} "
                 "ms; durable {:.1f} ms after its point; the writer thread encoded it in {:.1f} ms first",
                 written.seq, record.records, static_cast<double>(record.file_bytes) / 1e6, snapshots_.ms,
                 snapshots_.save_ms, snapshots_.write_ms, snapshots_.sync_ms, snapshots_.total_ms,
                 snapshots_.encode_ms);
}

void Journal::finish_snapshot() {
  if (!writer_ || !in_flight_) return;
  writer_->wait_idle();
  if (auto written = writer_->take_written()) complete_snapshot(*written);
}

}  // namespace surfeledit::service
