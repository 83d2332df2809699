#include "journal.hpp"

#include <algorithm>
#include <condition_variable>
#include <mutex>

#include "journal_records.hpp"
#include "journal_snapshot.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "surfeledit/service/decode.hpp"
#include "surfeledit/service/log.hpp"

namespace surfeledit::service {

namespace {

constexpr std::size_t kMaxKeptForLater = 64;  // deferred requests whose CDR waits for their reply

std::string str_of(const char* s) { return s ? std::string(s) : std::string(); }

// Signalled by the handler's loading threads during replay.
struct LoadSignal {
  std::mutex mutex;
  std::condition_variable cv;
  bool done = false;
};

// Re-serves a deferred request (OP_LOAD_FILE) to its end: waits for the load and commits it.
std::shared_ptr<const Reply> finish_deferred(Handler& handler, LoadSignal& signal, const Command& command) {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(signal.mutex);
      signal.cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return signal.done; });
      signal.done = false;
    }
    std::vector<UpdateEvent> ignored;
    std::shared_ptr<const Reply> found;
    for (auto& reply : handler.finish_loads(ignored)) {
      if (reply->client_id == command.client_id && reply->request_id == command.request_id) found = reply;
    }
    if (found) return found;
  }
}

}  // namespace

Journal::Journal(const JournalConfig& config, Handler& handler) : config_(config), handler_(handler) {
  if (config_.sync == JournalSync::Group && (config_.group_ms == 0 || config_.group_ms > 10'000)) {
    throw JournalError("journal group commit interval must be in 1..10000 ms");
  }
  if (config_.rejoin_ms == 0 || config_.rejoin_ms > 3'600'000) {
    throw JournalError("journal rejoin time must be in 1..3600000 ms");
  }
  if (config_.snapshot_mb > (std::uint64_t(1) << 20)) throw JournalError("journal snapshot size must be at most 1 TiB");
  const auto t0 = Clock::now();
  LoadSignal signal;
  handler.set_on_load_done([&signal] {
    std::lock_guard<std::mutex> lock(signal.mutex);
    signal.done = true;
    signal.cv.notify_all();
  });
  try {
    log_ = std::make_unique<JournalLog>(config_.dir);
    const std::size_t from = restore_newest_snapshot(handler);
    log_->read(from, [&](RecordKind kind, const std::vector<std::uint8_t>& payload) {
      try {
        replay(kind, payload, handler, [&](const Command& c) { return finish_deferred(handler, signal, c); });
        ++recovery_.replayed;
      } catch (const JournalError&) {
        throw;
      } catch (const std::exception& e) {
        throw JournalError("journal record " + std::to_string(from + recovery_.replayed + 1) +
                           " could not be replayed: " + e.what());
      }
    });
  } catch (...) {
    handler.set_on_load_done({});
    throw;
  }
  handler.set_on_load_done({});
  handler.start_recovered_leases(std::chrono::milliseconds(config_.rejoin_ms));
  // Snapshots count from the current segment's start. Snapshot k is the state at the start of segment k
  // (its record follows somewhere in segment k), and its record counts the records before that start.
  const auto& index = log_->index();
  since_snapshot_ = static_cast<std::uint64_t>(
      std::count_if(index.begin(), index.end(), [&](const JournalLog::RecordRef& r) { return r.segment == log_->segment(); }));
  total_records_ = index.size();
  for (std::size_t i = 0; i < index.size(); ++i) {
    if (index[i].kind != RecordKind::Snapshot) continue;
    const journal::SnapshotRecord first = journal::decode_snapshot(log_->payload(i));
    total_records_ += first.records - segment_start(first.seq);
    break;
  }
  // A snapshot's temporary file is never complete after a stop (a crash while it was written).
  journal::remove_snapshots_before(config_.dir, log_->dir_fd(), 0);
  if (config_.snapshot_records || config_.snapshot_mb) {
    start_writer();
    writer_->prepare(log_->segment() + 1);  // the first snapshot's segment, ahead
  }
  recovery_.bytes = log_->bytes();
  recovery_.cut_bytes = log_->cut_bytes();
  recovery_.ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  logger()->info("journal '{}': recovered {} request(s), {} refusal(s), {} expiries from {:.1f} MB in {:.0f} ms: "
                 "{}, {} record(s) replayed{}",
                 log_->path(), recovery_.requests, recovery_.refusals, recovery_.expiries,
                 static_cast<double>(recovery_.bytes) / 1e6, recovery_.ms,
                 recovery_.snapshot ? "snapshot " + std::to_string(recovery_.snapshot) + " restored (" +
                                          std::to_string(recovery_.skipped) + " record(s) before it not replayed)"
                                    : std::string("no snapshot"),
                 recovery_.replayed, recovery_.cut_bytes ? " (a torn tail was cut)" : "");
}

std::size_t Journal::segment_start(std::uint64_t segment) const {
  const auto& index = log_->index();
  return static_cast<std::size_t>(
      std::find_if(index.begin(), index.end(), [&](const JournalLog::RecordRef& r) { return r.segment >= segment; }) -
      index.begin());
}

std::size_t Journal::restore_newest_snapshot(Handler& handler) {
  const auto& index = log_->index();
  for (std::size_t i = index.size(); i-- > 0;) {
    if (index[i].kind != RecordKind::Snapshot) continue;
    const journal::SnapshotRecord record = journal::decode_snapshot(log_->payload(i));
    try {
      if (record.seq != index[i].segment) {
        throw JournalError("its record is in segment " + std::to_string(index[i].segment));
      }
      const std::string bytes = journal::read_snapshot_file(config_.dir, record);
      SnapshotReader in(bytes.data() + journal::kSnapshotHeaderBytes, bytes.size() - journal::kSnapshotHeaderBytes);
      handler.restore(in);  // reads and checks everything before it changes anything
    } catch (const std::exception& e) {
      logger()->warn("journal: snapshot {} (record {}) not restored: {}; falling back to an older snapshot or the "
                     "log's start",
                     record.seq, i + 1, e.what());
      continue;
    }
    // The state at the start of its segment: every record of the segment is replayed (its own record
    // and any other Snapshot record replay as nothing).
    const std::size_t from = segment_start(record.seq);
    recovery_.snapshot = record.seq;
    recovery_.skipped = from;
    kept_snapshot_ = record.seq;
    return from;
  }
  if (log_->first_segment() != 0) {
    throw JournalError("journal '" + config_.dir + "': no snapshot in it could be restored and the log before segment " +
                       std::to_string(log_->first_segment()) + " was deleted: not recovered (see the lines above)");
  }
  return 0;
}

void Journal::replay(RecordKind kind, const std::vector<std::uint8_t>& payload, Handler& handler,
                     const std::function<std::shared_ptr<const Reply>(const Command&)>& wait_deferred) {
  std::vector<UpdateEvent> ignored;
  switch (kind) {
    case RecordKind::Request: {
      journal::RequestRecord record = journal::decode_request(payload);
      journal::RequestSample sample(std::move(record.cdr));
      Command command = decode(sample.get());
      command.sender = 0;  // bind nothing: the client rebinds with its new writer
      handler.set_next_token(record.token);
      std::shared_ptr<const Reply> reply = handler.handle(command, ignored);
      if (!reply) reply = wait_deferred(command);  // OP_LOAD_FILE: its load, committed
      const std::string who = command.client_id + "#" + std::to_string(command.request_id) + " " + op_name(command.op);
      if (reply->status != Status::Ok) {
        throw JournalError("journal: request " + who + " was accepted but is refused on replay (" + reply->field +
                           ": " + reply->message + ")");
      }
      if (reply->version != record.version) {
        throw JournalError("journal: request " + who + " replays to version " + std::to_string(reply->version) +
                           ", the journal recorded version " + std::to_string(record.version));
      }
      if (record.state_hash && (!reply->session_info || reply->session_info->state_hash != *record.state_hash)) {
        throw JournalError("journal: request " + who + " replays to another state than it recorded (state hash "
                           "differs; for OP_LOAD_FILE: the file changed since)");
      }
      ++recovery_.requests;
      return;
    }
    case RecordKind::Refusal:
      handler.remember(journal::reply_of(journal::decode_refusal(payload)));
      ++recovery_.refusals;
      return;
    case RecordKind::Expiry:
      handler.apply_expiry(journal::decode_expiry(payload).expiry, ignored);
      ++recovery_.expiries;
      return;
    case RecordKind::Snapshot:  // the one restored, or one newer: not usable; its state is replayed
      return;
  }
}

void Journal::keep_for_later(const surfeledit_proto_Request& request) {
  auto key = std::make_pair(str_of(request.client_id), request.request_id);
  if (later_.count(key)) return;
  try {
    later_[key] = journal::request_cdr(request);
  } catch (const std::exception& e) {
    failure_ = e.what();
    return;
  }
  later_order_.push_back(key);
  while (later_order_.size() > kMaxKeptForLater) {
    later_.erase(later_order_.front());
    later_order_.pop_front();
  }
}

void Journal::on_stored(const Reply& reply) {
  if (failed()) return;
  try {
    if (reply.status != Status::Ok) {
      append(RecordKind::Refusal, journal::encode(journal::refusal_of(reply)));
      later_.erase({reply.client_id, reply.request_id});
      return;
    }
    journal::RequestRecord record;
    record.version = reply.version;
    if (reply.session_info) record.state_hash = reply.session_info->state_hash;
    record.token = reply.token;
    if (serving_ && str_of(serving_->client_id) == reply.client_id && serving_->request_id == reply.request_id) {
      record.cdr = journal::request_cdr(*serving_);
    } else {
      auto it = later_.find({reply.client_id, reply.request_id});
      if (it == later_.end()) {
        throw JournalError("the request " + reply.client_id + "#" + std::to_string(reply.request_id) +
                           " is no longer known");
      }
      record.cdr = std::move(it->second);
      later_.erase(it);
    }
    append(RecordKind::Request, journal::encode(record));
  } catch (const std::exception& e) {
    failure_ = std::string("journal: ") + e.what();
    logger()->critical("{}: no more replies are sent", failure_);
  }
}

void Journal::on_expired(const Expiry& expiry) {
  if (failed()) return;
  try {
    append(RecordKind::Expiry, journal::encode(journal::ExpiryRecord{expiry}));
  } catch (const std::exception& e) {
    failure_ = std::string("journal: ") + e.what();
    logger()->critical("{}: no more replies are sent", failure_);
  }
}

void Journal::append(RecordKind kind, const std::vector<std::uint8_t>& payload) {
  log_->append(kind, payload);
  ++since_snapshot_;
  ++total_records_;
  if (config_.sync == JournalSync::Op) {
    log_->sync();
    return;
  }
  ++unsynced_;
  if (!deadline_) deadline_ = Clock::now() + std::chrono::milliseconds(config_.group_ms);
}

void Journal::after_durable(std::function<void()> release) {
  if (failed()) return;  // never acknowledged: the client retries after the restart
  if (idle()) {
    release();
    return;
  }
  waiting_.push_back(std::move(release));
  if (!deadline_) deadline_ = Clock::now() + std::chrono::milliseconds(config_.group_ms);
}

void Journal::flush(bool force) {
  if (!deadline_ || failed()) return;
  if (!force && Clock::now() < *deadline_) return;
  if (unsynced_ > 0) {
    try {
      log_->sync();
    } catch (const std::exception& e) {
      failure_ = e.what();
      logger()->critical("{}: no more replies are sent", failure_);
      waiting_.clear();
      return;
    }
  }
  unsynced_ = 0;
  deadline_.reset();
  std::vector<std::function<void()>> ready;
  ready.swap(waiting_);
  for (auto& release : ready) release();
}

}  // namespace surfeledit::service
