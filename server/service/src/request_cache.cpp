#include "surfeledit/service/request_cache.hpp"

#include <stdexcept>

namespace surfeledit::service {

RequestCache::RequestCache(std::size_t per_client, std::size_t max_clients)
    : per_client_(per_client), max_clients_(max_clients) {
  if (per_client_ == 0 || max_clients_ == 0) throw std::invalid_argument("RequestCache limits must be positive");
}

RequestCache::ClientReplies& RequestCache::touch(const std::string& client_id) {
  auto it = clients_.find(client_id);
  if (it != clients_.end()) {
    activity_.splice(activity_.begin(), activity_, it->second.activity);
    return it->second;
  }
  while (clients_.size() >= max_clients_) {
    clients_.erase(activity_.back());
    activity_.pop_back();
  }
  activity_.push_front(client_id);
  ClientReplies& c = clients_[client_id];
  c.activity = activity_.begin();
  return c;
}

std::shared_ptr<const Reply> RequestCache::find(const std::string& client_id, std::uint64_t request_id) {
  auto cit = clients_.find(client_id);
  if (cit == clients_.end()) return nullptr;
  ClientReplies& c = cit->second;
  auto rit = c.by_id.find(request_id);
  if (rit == c.by_id.end()) return nullptr;
  c.order.splice(c.order.begin(), c.order, rit->second);
  activity_.splice(activity_.begin(), activity_, c.activity);
  return *rit->second;
}

void RequestCache::put(std::shared_ptr<const Reply> reply) {
  if (!reply) throw std::invalid_argument("RequestCache::put: null reply");
  ClientReplies& c = touch(reply->client_id);
  const std::uint64_t id = reply->request_id;
  auto rit = c.by_id.find(id);
  if (rit != c.by_id.end()) {
    c.order.erase(rit->second);
    c.by_id.erase(rit);
  }
  c.order.push_front(std::move(reply));
  c.by_id[id] = c.order.begin();
  while (c.order.size() > per_client_) {
    c.by_id.erase(c.order.back()->request_id);
    c.order.pop_back();
  }
}

void RequestCache::forget(const std::string& client_id) {
  auto it = clients_.find(client_id);
  if (it == clients_.end()) return;
  activity_.erase(it->second.activity);
  clients_.erase(it);
}

std::size_t RequestCache::size(const std::string& client_id) const {
  auto it = clients_.find(client_id);
  return it == clients_.end() ? 0 : it->second.order.size();
}

}  // namespace surfeledit::service
