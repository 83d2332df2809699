#include "surfeledit/service/request_cache.hpp"

#include <stdexcept>

namespace surfeledit::service {

namespace {

constexpr std::size_t kReplyOverhead = 512;  // bytes: the Reply object, its cache slot and list nodes

template <typename T>
std::size_t vec_bytes(const std::vector<T>& v) {
  return v.size() * sizeof(T);
}

}  // namespace

std::size_t reply_bytes(const Reply& r) {
  std::size_t n = kReplyOverhead + r.client_id.size() + r.field.size() + r.message.size() + r.token.size();
  for (const auto& t : r.timings) n += t.first.size() + sizeof(double) + 32;
  if (r.state) {
    const StatePage& p = *r.state;
    n += vec_bytes(p.ids) + vec_bytes(p.positions) + vec_bytes(p.normals) + vec_bytes(p.radii) + vec_bytes(p.removed) +
         vec_bytes(p.clip_points) + vec_bytes(p.clip_dirs);
  }
  if (r.session_info) {
    n += r.session_info->name.size() + 64 * (r.session_info->structures.size() + r.session_info->settings.size());
  }
  if (r.server_info) {
    for (const auto& s : r.server_info->sessions) n += s.size() + 32;
  }
  if (r.step) {
    n += vec_bytes(r.step->colliding) + vec_bytes(r.step->depths) + vec_bytes(r.step->inserted) +
         vec_bytes(r.step->features);
  }
  for (const auto& h : r.history) n += 64 + h.op.size() + h.client_id.size() + vec_bytes(h.touched);
  auto curve_bytes = [](const std::vector<CurveInfo>& curves) {
    std::size_t b = 0;
    for (const auto& c : curves) b += 32 + vec_bytes(c.points);
    return b;
  };
  n += curve_bytes(r.curves);
  if (r.merge) {
    n += vec_bytes(r.merge->removed) + vec_bytes(r.merge->features) + vec_bytes(r.merge->moved) +
         vec_bytes(r.merge->inserted) + curve_bytes(r.merge->curves);
  }
  return n;
}

RequestCache::RequestCache(RequestCacheLimits limits) : limits_(limits) {
  if (limits_.per_client == 0 || limits_.max_clients == 0 || limits_.max_bytes == 0) {
    throw std::invalid_argument("RequestCache limits must be positive");
  }
}

RequestCache::ClientReplies& RequestCache::touch(const std::string& client_id) {
  auto it = clients_.find(client_id);
  if (it != clients_.end()) {
    activity_.splice(activity_.begin(), activity_, it->second.activity);
    return it->second;
  }
  while (clients_.size() >= limits_.max_clients) drop_client(activity_.back());
  activity_.push_front(client_id);
  ClientReplies& c = clients_[client_id];
  c.activity = activity_.begin();
  return c;
}

void RequestCache::erase(ClientReplies& c, std::unordered_map<std::uint64_t, Slot>::iterator slot) {
  bytes_ -= slot->second.bytes;
  c.order.erase(slot->second.in_client);
  lru_.erase(slot->second.in_global);
  c.by_id.erase(slot);
}

void RequestCache::drop_client(const std::string& client_id) {
  auto it = clients_.find(client_id);
  if (it == clients_.end()) return;
  ClientReplies& c = it->second;
  while (!c.by_id.empty()) erase(c, c.by_id.begin());
  activity_.erase(c.activity);
  clients_.erase(it);
}

std::shared_ptr<const Reply> RequestCache::find(const std::string& client_id, std::uint64_t request_id) {
  auto cit = clients_.find(client_id);
  if (cit == clients_.end()) return nullptr;
  ClientReplies& c = cit->second;
  auto rit = c.by_id.find(request_id);
  if (rit == c.by_id.end()) return nullptr;
  c.order.splice(c.order.begin(), c.order, rit->second.in_client);
  lru_.splice(lru_.begin(), lru_, rit->second.in_global);
  activity_.splice(activity_.begin(), activity_, c.activity);
  return rit->second.reply;
}

void RequestCache::put(std::shared_ptr<const Reply> reply, std::optional<std::size_t> bytes) {
  if (!reply) throw std::invalid_argument("RequestCache::put: null reply");
  const std::string client_id = reply->client_id;
  const std::uint64_t id = reply->request_id;
  const std::size_t size = bytes ? *bytes : reply_bytes(*reply);
  {
    ClientReplies& c = touch(client_id);
    auto rit = c.by_id.find(id);
    if (rit != c.by_id.end()) erase(c, rit);
    if (size > limits_.max_bytes) {
      if (c.by_id.empty()) drop_client(client_id);
      return;
    }
    c.order.push_front(id);
    lru_.emplace_front(client_id, id);
    c.by_id[id] = Slot{std::move(reply), size, c.order.begin(), lru_.begin()};
    bytes_ += size;
    while (c.order.size() > limits_.per_client) erase(c, c.by_id.find(c.order.back()));
  }
  // The byte bound: least recently used replies of any client first (never the one just stored).
  while (bytes_ > limits_.max_bytes && lru_.size() > 1) {
    const Key oldest = lru_.back();
    ClientReplies& c = clients_.at(oldest.first);
    erase(c, c.by_id.find(oldest.second));
    if (c.by_id.empty() && oldest.first != client_id) drop_client(oldest.first);
  }
}

void RequestCache::for_each_oldest_first(const std::function<void(const Reply&, std::size_t)>& fn) const {
  for (auto it = lru_.rbegin(); it != lru_.rend(); ++it) {
    const Slot& slot = clients_.at(it->first).by_id.at(it->second);
    fn(*slot.reply, slot.bytes);
  }
}

void RequestCache::forget(const std::string& client_id) { drop_client(client_id); }

std::size_t RequestCache::size(const std::string& client_id) const {
  auto it = clients_.find(client_id);
  return it == clients_.end() ? 0 : it->second.order.size();
}

}  // namespace surfeledit::service
