#include "reply_writers.hpp"

#include <utility>

namespace surfeledit::service {

namespace {

// Replies a late-matching reader still receives (a client has one request in flight at a time).
constexpr int32_t kReplyDepth = 4;

}  // namespace

std::string reply_partition(const std::string& client_id) { return "surfeledit.reply." + client_id; }

ReplyWriters::ReplyWriters(const dds::Entity& participant, const dds::Entity& topic, dds_duration_t liveliness)
    : participant_(participant), topic_(topic), liveliness_(liveliness), deleter_([this] { delete_retired(); }) {}

ReplyWriters::~ReplyWriters() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  deleter_.join();
}

const dds::Entity& ReplyWriters::for_client(const std::string& client_id) {
  auto it = writers_.find(client_id);
  if (it != writers_.end()) return it->second.writer;
  dds::Qos pub_qos;
  pub_qos.partition(reply_partition(client_id));
  ClientWriter w;
  w.publisher = dds::make_publisher(participant_, pub_qos);
  dds::Qos qos = dds::protocol_qos();
  qos.automatic_liveliness(liveliness_).transient_local(kReplyDepth);
  w.writer = dds::make_writer(w.publisher, topic_, qos);
  return writers_.emplace(client_id, std::move(w)).first->second.writer;
}

void ReplyWriters::drop(const std::string& client_id) {
  auto it = writers_.find(client_id);
  if (it == writers_.end()) return;
  ClientWriter retired = std::move(it->second);
  writers_.erase(it);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    retired_.push_back(std::move(retired));
  }
  wake_.notify_one();
}

std::size_t ReplyWriters::retiring() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return retired_.size();
}

void ReplyWriters::delete_retired() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_ || !retired_.empty(); });
    if (retired_.empty()) return;  // stopping, nothing left
    // Deleted outside the lock (dds_delete may linger): the request thread keeps dropping meanwhile.
    ClientWriter w = std::move(retired_.front());
    lock.unlock();
    w.writer.reset();
    w.publisher.reset();
    lock.lock();
    retired_.pop_front();
  }
}

}  // namespace surfeledit::service
