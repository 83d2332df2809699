// Idempotence: the last replies per client id, so that a repeated (client_id, request_id) is
// answered again with the stored reply instead of being applied twice. Bounded three ways: replies
// per client, clients, and estimated bytes of all stored replies (the least recently used reply
// of any client goes first). The handler looks a request up only after its client id was checked
// against the sending writer, so another writer can neither fill nor read a client's entries.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <list>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>

#include "surfeledit/service/reply.hpp"

namespace surfeledit::service {

// Estimated memory of a reply: its strings and arrays plus a fixed overhead, in bytes.
std::size_t reply_bytes(const Reply& reply);

struct RequestCacheLimits {
  std::size_t per_client = 1024;               // replies remembered per client (least recently used evicted first)
  std::size_t max_clients = 4096;              // clients remembered (the least recently active forgotten first)
  std::size_t max_bytes = std::size_t(64) << 20;  // reply_bytes() of all stored replies
};

class RequestCache {
 public:
  explicit RequestCache(RequestCacheLimits limits = {});
  explicit RequestCache(std::size_t per_client, std::size_t max_clients = 4096)
      : RequestCache(RequestCacheLimits{per_client, max_clients}) {}

  // The stored reply for this request, or nullptr; a hit counts as a use.
  std::shared_ptr<const Reply> find(const std::string& client_id, std::uint64_t request_id);
  // Stores (or replaces) the reply of `reply.client_id`, `reply.request_id`. A reply larger than
  // the byte bound is not stored.
  // `bytes`: its reply_bytes() when it was first stored (a reply restored from a snapshot).
  void put(std::shared_ptr<const Reply> reply, std::optional<std::size_t> bytes = std::nullopt);
  // Every stored reply with its counted bytes, least recently used first (putting them in this order
  // rebuilds the same order).
  void for_each_oldest_first(const std::function<void(const Reply&, std::size_t bytes)>& fn) const;
  // Forgets everything about a client.
  void forget(const std::string& client_id);

  std::size_t clients() const { return clients_.size(); }
  std::size_t size(const std::string& client_id) const;
  std::size_t bytes() const { return bytes_; }
  const RequestCacheLimits& limits() const { return limits_; }

 private:
  using Key = std::pair<std::string, std::uint64_t>;  // client id, request id
  struct Slot {
    std::shared_ptr<const Reply> reply;
    std::size_t bytes = 0;
    std::list<std::uint64_t>::iterator in_client;  // position in ClientReplies::order
    std::list<Key>::iterator in_global;            // position in lru_
  };
  // One client's replies, most recently used first.
  struct ClientReplies {
    std::list<std::uint64_t> order;
    std::unordered_map<std::uint64_t, Slot> by_id;
    std::list<std::string>::iterator activity;  // position in activity_
  };
  ClientReplies& touch(const std::string& client_id);
  void erase(ClientReplies& c, std::unordered_map<std::uint64_t, Slot>::iterator slot);
  void drop_client(const std::string& client_id);

  RequestCacheLimits limits_;
  std::size_t bytes_ = 0;
  std::unordered_map<std::string, ClientReplies> clients_;
  std::list<std::string> activity_;  // client ids, most recently active first
  std::list<Key> lru_;               // every stored reply, most recently used first
};

}  // namespace surfeledit::service
