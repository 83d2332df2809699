#include "surfeledit/service/client_registry.hpp"

namespace surfeledit::service {

bool ClientRegistry::admit(const std::string& id, std::uint64_t sender, LeaseClock::time_point now) {
  auto it = clients_.find(id);
  if (it == clients_.end()) {
    if (by_sender_.count(sender) >= max_ids_per_writer_) return false;
    ClientRecord record;
    record.sender = sender;
    record.first_seen = now;
    it = clients_.emplace(id, record).first;
    by_sender_.emplace(sender, id);
  } else if (it->second.sender == 0 && sender != 0) {
    // Recovered from the journal: the first writer to use the id after the restart binds it.
    if (by_sender_.count(sender) >= max_ids_per_writer_) return false;
    it->second.sender = sender;
    by_sender_.emplace(sender, id);
  } else if (it->second.sender != sender) {
    return false;
  }
  it->second.last_activity = now;
  it->second.gone_since.reset();  // a request from the writer proves it alive
  ++it->second.requests;
  return true;
}

void ClientRegistry::recovered(const std::string& id, LeaseClock::time_point gone_since) {
  if (clients_.count(id)) return;
  ClientRecord record;
  record.first_seen = LeaseClock::now();
  record.last_activity = record.first_seen;
  record.gone_since = gone_since;
  clients_.emplace(id, record);
}

void ClientRegistry::writer_lost(std::uint64_t sender, LeaseClock::time_point now) {
  auto [first, last] = by_sender_.equal_range(sender);
  for (auto it = first; it != last; ++it) {
    ClientRecord& record = clients_.at(it->second);
    if (!record.gone_since) record.gone_since = now;
  }
}

void ClientRegistry::writer_alive(std::uint64_t sender) {
  auto [first, last] = by_sender_.equal_range(sender);
  for (auto it = first; it != last; ++it) clients_.at(it->second).gone_since.reset();
}

std::vector<std::string> ClientRegistry::expired(LeaseClock::time_point now, LeaseClock::duration lease) const {
  std::vector<std::string> out;
  for (const auto& [id, record] : clients_) {
    if (record.gone_since && now - *record.gone_since >= lease) out.push_back(id);
  }
  return out;
}

std::optional<LeaseClock::time_point> ClientRegistry::next_expiry(LeaseClock::duration lease) const {
  std::optional<LeaseClock::time_point> next;
  for (const auto& kv : clients_) {
    if (!kv.second.gone_since) continue;
    const LeaseClock::time_point end = *kv.second.gone_since + lease;
    if (!next || end < *next) next = end;
  }
  return next;
}

void ClientRegistry::forget(const std::string& id) {
  auto it = clients_.find(id);
  if (it == clients_.end()) return;
  auto [first, last] = by_sender_.equal_range(it->second.sender);
  for (auto s = first; s != last; ++s) {
    if (s->second == id) {
      by_sender_.erase(s);
      break;
    }
  }
  clients_.erase(it);
}

const ClientRecord* ClientRegistry::find(const std::string& id) const {
  auto it = clients_.find(id);
  return it == clients_.end() ? nullptr : &it->second;
}

}  // namespace surfeledit::service
