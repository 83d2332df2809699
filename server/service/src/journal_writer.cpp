#include "journal_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <utility>

#include "surfeledit/service/log.hpp"

namespace surfeledit::service::journal {

SnapshotThread::SnapshotThread(std::string dir, std::function<void()> on_written)
    : dir_(std::move(dir)), on_written_(std::move(on_written)) {
  dir_fd_ = UniqueFd(::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir_fd_.get() < 0) fail("cannot open journal directory '" + dir_ + "'", errno);
  thread_ = std::thread([this] { run(); });
}

SnapshotThread::~SnapshotThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void SnapshotThread::push(Job job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (job.kind == Kind::Write) {
      if (in_flight_) {
        throw JournalError("journal: snapshot " + std::to_string(job.seq) + " handed over while another is in flight");
      }
      in_flight_ = true;
    }
    jobs_.push_back(std::move(job));
  }
  wake_.notify_one();
}

void SnapshotThread::write(std::uint64_t seq, std::vector<std::string> parts) {
  write(seq, [ready = std::move(parts)](std::vector<std::string>& out) mutable { out = std::move(ready); });
}

void SnapshotThread::write(std::uint64_t seq, Encoder encode) {
  Job job;
  job.seq = seq;
  job.encode = std::move(encode);
  push(std::move(job));
}

void SnapshotThread::remove(std::vector<std::string> segments, std::uint64_t snapshots_before) {
  Job job;
  job.kind = Kind::Remove;
  job.seq = snapshots_before;
  job.segments = std::move(segments);
  push(std::move(job));
}

void SnapshotThread::prepare(std::uint64_t segment) {
  Job job;
  job.kind = Kind::Prepare;
  job.seq = segment;
  push(std::move(job));
}

std::uint64_t SnapshotThread::prepared() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return prepared_;
}

bool SnapshotThread::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return in_flight_;
}

std::optional<WrittenSnapshot> SnapshotThread::take_written() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<WrittenSnapshot> out;
  out.swap(written_);
  if (out) in_flight_ = false;
  return out;
}

void SnapshotThread::wait_idle() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return jobs_.empty() && !working_; });
}

void SnapshotThread::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
    if (jobs_.empty()) return;  // stop, with nothing left to do
    Job job = std::move(jobs_.front());
    jobs_.pop_front();
    working_ = true;
    lock.unlock();
    if (job.kind == Kind::Remove) {
      remove_files(job);
    } else if (job.kind == Kind::Prepare) {
      std::uint64_t made = 0;
      try {
        JournalLog::create_segment(dir_, dir_fd_.get(), job.seq);
        made = job.seq;
      } catch (const std::exception& e) {
        logger()->warn("journal: segment {} not created ahead: {}; the snapshot's point creates it", job.seq, e.what());
      }
      lock.lock();
      prepared_ = made;
      lock.unlock();
    } else {
      WrittenSnapshot done;
      done.seq = job.seq;
      try {
        const auto t0 = std::chrono::steady_clock::now();
        job.encode(job.parts);
        job.encode = nullptr;  // what it held (history images shared with the session) is let go here
        done.encode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        done.record = write_snapshot_file(dir_, dir_fd_.get(), job.seq, job.parts, &done.times);
      } catch (const std::exception& e) {
        done.error = e.what();
      }
      job.encode = nullptr;
      job.parts.clear();
      job.parts.shrink_to_fit();  // the snapshot's bytes are freed here, not on the request thread
      lock.lock();
      written_ = std::move(done);
      lock.unlock();
      if (on_written_) on_written_();
    }
    lock.lock();
    working_ = false;
    if (jobs_.empty()) idle_.notify_all();
  }
}

void SnapshotThread::remove_files(const Job& job) {
  try {
    for (const std::string& path : job.segments) {
      if (::unlink(path.c_str()) != 0 && errno != ENOENT) fail("cannot remove journal segment '" + path + "'", errno);
    }
    remove_snapshots_before(dir_, dir_fd_.get(), job.seq);
    if (!job.segments.empty()) sync_dir(dir_fd_.get(), dir_);
  } catch (const std::exception& e) {
    logger()->warn("journal: old segments or snapshots not removed: {}", e.what());
  }
}

}  // namespace surfeledit::service::journal
