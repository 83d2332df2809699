// Who is who: each client id is bound to the DDS writer (publication handle) that first used it;
// a request claiming a bound id from another writer is refused. The registry also keeps when a
// client was last active and since when its writer is gone (not alive or unmatched), so the
// handler can detach clients whose lease ran out. Issue 11 (collaboration) hangs per-client
// tools and presence off these records; roles per session live in SessionEntry::members.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace surfeledit::service {

using LeaseClock = std::chrono::steady_clock;

struct ClientRecord {
  std::uint64_t sender = 0;                 // publication handle of the bound request writer (0: none yet)
  LeaseClock::time_point first_seen;        // when the id was bound
  LeaseClock::time_point last_activity;     // last request admitted
  std::optional<LeaseClock::time_point> gone_since;  // the writer is not alive / unmatched since
  std::uint64_t requests = 0;               // requests admitted
};

class ClientRegistry {
 public:
  // `max_ids_per_writer`: client ids one writer may bind (more are refused).
  explicit ClientRegistry(std::size_t max_ids_per_writer = 16) : max_ids_per_writer_(max_ids_per_writer) {}

  // True when `id` is bound to `sender` (binding it now when the id is new); false when the id is
  // bound to another writer, or the writer already holds its maximum of ids.
  bool admit(const std::string& id, std::uint64_t sender, LeaseClock::time_point now);
  // A client recovered from the journal, bound to no writer yet: its lease runs as if its writer was
  // gone since `gone_since`, until its first request (from any writer, which it is then bound to).
  void recovered(const std::string& id, LeaseClock::time_point gone_since);
  // The writer lost its liveliness or was unmatched: its clients' leases start running (once).
  void writer_lost(std::uint64_t sender, LeaseClock::time_point now);
  // The writer is alive again: its clients' leases stop.
  void writer_alive(std::uint64_t sender);
  // Clients whose writer has been gone for at least `lease`.
  std::vector<std::string> expired(LeaseClock::time_point now, LeaseClock::duration lease) const;
  // The earliest time a running lease ends (nullopt: none runs).
  std::optional<LeaseClock::time_point> next_expiry(LeaseClock::duration lease) const;
  void forget(const std::string& id);

  const ClientRecord* find(const std::string& id) const;
  std::size_t size() const { return clients_.size(); }

 private:
  std::size_t max_ids_per_writer_;
  std::map<std::string, ClientRecord> clients_;
  std::multimap<std::uint64_t, std::string> by_sender_;
};

}  // namespace surfeledit::service
