// Idempotence: the last replies per client id, so that a repeated (client_id, request_id) is
// answered again with the stored reply instead of being applied twice.
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <string>
#include <unordered_map>

#include "surfeledit/service/reply.hpp"

namespace surfeledit::service {

class RequestCache {
 public:
  // `per_client`: replies remembered per client (least recently used evicted first);
  // `max_clients`: clients remembered (the least recently active one is forgotten first).
  explicit RequestCache(std::size_t per_client = 1024, std::size_t max_clients = 4096);

  // The stored reply for this request, or nullptr; a hit counts as a use.
  std::shared_ptr<const Reply> find(const std::string& client_id, std::uint64_t request_id);
  // Stores (or replaces) the reply of `reply.client_id`, `reply.request_id`.
  void put(std::shared_ptr<const Reply> reply);
  // Forgets everything about a client.
  void forget(const std::string& client_id);

  std::size_t clients() const { return clients_.size(); }
  std::size_t size(const std::string& client_id) const;

 private:
  // One client's replies, most recently used first.
  struct ClientReplies {
    std::list<std::shared_ptr<const Reply>> order;
    std::unordered_map<std::uint64_t, std::list<std::shared_ptr<const Reply>>::iterator> by_id;
    std::list<std::string>::iterator activity;  // position in activity_
  };
  ClientReplies& touch(const std::string& client_id);

  std::size_t per_client_;
  std::size_t max_clients_;
  std::unordered_map<std::string, ClientReplies> clients_;
  std::list<std::string> activity_;  // client ids, most recently active first
};

}  // namespace surfeledit::service
