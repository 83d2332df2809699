#include "reply_writers.hpp"

namespace surfeledit::service {

namespace {

// Replies a late-matching reader still receives (a client has one request in flight at a time).
constexpr int32_t kReplyDepth = 4;

}  // namespace

std::string reply_partition(const std::string& client_id) { return "surfeledit.reply." + client_id; }

ReplyWriters::ReplyWriters(const dds::Entity& participant, const dds::Entity& topic, dds_duration_t liveliness)
    : participant_(participant), topic_(topic), liveliness_(liveliness) {}

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

void ReplyWriters::drop(const std::string& client_id) { writers_.erase(client_id); }

}  // namespace surfeledit::service
