#include "surfeledit/service/update_publisher.hpp"

#include <algorithm>
#include <exception>
#include <utility>

#include "surfeledit/service/log.hpp"

namespace surfeledit::service {

UpdatePublisher::UpdatePublisher(Writer writer, std::size_t max_queued_bytes)
    : writer_(std::move(writer)), max_bytes_(max_queued_bytes) {
  if (!writer_) throw std::invalid_argument("update publisher needs a writer");
  if (max_bytes_ == 0) throw std::invalid_argument("max_queued_bytes must be positive");
  thread_ = std::thread([this] { run(); });
}

UpdatePublisher::~UpdatePublisher() { shutdown(); }

bool UpdatePublisher::enqueue(PreparedUpdate& update, bool bounded) {
  const std::size_t b = update.bytes();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return false;
    if (bounded && !queue_.empty() && bytes_ + b > max_bytes_) return false;
    bytes_ += b;
    counters_.max_queued_bytes = std::max(counters_.max_queued_bytes, bytes_);
    counters_.queued += 1;
    queue_.push_back(std::move(update));
  }
  wake_.notify_one();
  return true;
}

bool UpdatePublisher::push(PreparedUpdate& update) { return enqueue(update, true); }

bool UpdatePublisher::push_anyway(PreparedUpdate&& update) { return enqueue(update, false); }

std::vector<PreparedUpdate> UpdatePublisher::take_pending(const std::string& session, std::uint64_t next_version,
                                                          const std::vector<std::string>& incremental) {
  std::vector<PreparedUpdate> out;
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < queue_.size(); ++i) {
    if (queue_[i].session == session) at.push_back(i);
  }
  if (at.empty()) return out;
  // Exactly consecutive versions ending right before next_version, all incremental.
  const std::uint64_t first = queue_[at.front()].version;
  for (std::size_t k = 0; k < at.size(); ++k) {
    const PreparedUpdate& u = queue_[at[k]];
    if (u.version != first + k) return out;
    if (std::find(incremental.begin(), incremental.end(), u.cause) == incremental.end()) return out;
  }
  if (first + at.size() != next_version) return out;
  out.reserve(at.size());
  for (std::size_t i : at) {
    bytes_ -= queue_[i].bytes();
    out.push_back(std::move(queue_[i]));
  }
  for (auto it = at.rbegin(); it != at.rend(); ++it) queue_.erase(queue_.begin() + static_cast<std::ptrdiff_t>(*it));
  counters_.taken_back += out.size();
  if (queue_.empty() && !busy_) idle_.notify_all();
  return out;
}

void UpdatePublisher::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) break;  // stopping and drained
    if (stopping_ && std::chrono::steady_clock::now() > drain_until_) break;
    PreparedUpdate update = std::move(queue_.front());
    queue_.pop_front();
    bytes_ -= update.bytes();
    busy_ = true;
    lock.unlock();
    bool ok = true;
    try {
      writer_(update);
    } catch (const std::exception& e) {
      ok = false;
      logger()->warn("update of session '{}' v{} ({}) not published: {}", update.session, update.version,
                     update.cause, e.what());
    }
    lock.lock();
    busy_ = false;
    (ok ? counters_.published : counters_.failed) += 1;
    if (queue_.empty()) idle_.notify_all();
  }
}

UpdatePublisher::Counters UpdatePublisher::shutdown(std::chrono::milliseconds drain_deadline) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!stopping_) {
      stopping_ = true;
      drain_until_ = std::chrono::steady_clock::now() + drain_deadline;
      if (!queue_.empty()) {
        logger()->info("publishing {} queued update(s) ({:.1f} MB) before exit, for at most {} ms", queue_.size(),
                       static_cast<double>(bytes_) / 1e6, drain_deadline.count());
      }
    }
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  if (!queue_.empty()) {
    logger()->warn("dropped {} queued update(s) ({:.1f} MB) at exit: the drain deadline passed", queue_.size(),
                   static_cast<double>(bytes_) / 1e6);
    counters_.dropped += queue_.size();
    queue_.clear();
    bytes_ = 0;
    idle_.notify_all();
  }
  return counters_;
}

UpdatePublisher::Counters UpdatePublisher::counters() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

std::size_t UpdatePublisher::queued_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

std::size_t UpdatePublisher::queued_updates() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.size();
}

void UpdatePublisher::wait_idle() const {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [&] { return queue_.empty() && !busy_; });
}

}  // namespace surfeledit::service
