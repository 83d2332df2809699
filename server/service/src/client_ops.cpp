// Clients: role checks, OP_INVITE, and leases (detaching clients whose request writer is gone).
#include "handler_ops.hpp"
#include "surfeledit/service/log.hpp"

#include <utility>

namespace surfeledit::service {

void check_role(const SessionEntry& entry, const Command& command) {
  const Role needed = required_role(static_cast<std::uint32_t>(command.op));
  const Role* role = entry.role_of(command.client_id);
  const Role have = role ? *role : Role::Viewer;
  if (have >= needed) return;
  throw PermissionDenied("session", "client '" + command.client_id + "' is " + (role ? "a" : "no member,") + " " +
                                        role_name(have) + " of session '" + command.session + "'; " +
                                        op_name(command.op) + " needs the role " + role_name(needed));
}

void serve_invite(OpContext& c) {
  const Role role = args_of<InviteArgs>(c).role;
  c.reply.token = c.state.sessions.invite(*c.entry, role, std::exchange(c.state.next_token, std::string()));
  logger()->info("client {} invited a {} to session '{}'", c.command.client_id, role_name(role), c.command.session);
}

void Handler::writer_lost(std::uint64_t sender) { state_->clients.writer_lost(sender, LeaseClock::now()); }

void Handler::writer_alive(std::uint64_t sender) { state_->clients.writer_alive(sender); }

namespace {

// Detaches a client whose lease ran out (Expiry::Lease): its tools released, a "presence" update "expired"
// per session (a session left without clients is kept for the grace period), its uploads, cached replies and
// id dropped; its memberships are kept for the grace period (HandlerState::away).
void detach_client(HandlerState& s, const std::string& client, LeaseClock::time_point now,
                   std::vector<UpdateEvent>& updates) {
  const std::uint64_t held = s.uploads.client_bytes(client);
  const std::vector<std::string> sessions = s.sessions.attached_to(client);
  s.away[client] = now;  // before the presence updates: they list it as away
  for (const std::string& name : sessions) {
    SessionEntry& entry = *s.sessions.find(name);
    release_tool(entry, name, client, updates);
    if (s.sessions.leave(name, client)) {
      entry.orphaned_since = now;
      logger()->info("session '{}' kept for {} ms: its last client {} was detached", name,
                     s.config.session_grace.count(), client);
    }
    updates.push_back(presence_event(s, entry, name, client, "expired"));
  }
  s.uploads.erase_client(client);
  s.cache.forget(client);
  s.clients.forget(client);
  logger()->info("client {} detached: its request writer was gone for {} ms ({} session(s) left, {} upload "
                 "bytes freed)",
                 client, s.config.client_lease.count(), sessions.size(), held);
}

// Drops a session nobody came back to (Expiry::Grace), with a "close" update.
void drop_orphan(HandlerState& s, const std::string& name, std::vector<UpdateEvent>& updates) {
  SessionEntry* entry = s.sessions.find(name);
  if (!entry) return;
  const std::uint64_t version = entry->session->version();
  s.uploads.erase_session(name);
  s.sessions.drop(name);
  updates.push_back(make_update_event(name, version + 1, "close"));
  logger()->info("session '{}' dropped: no client came back within {} ms", name, s.config.session_grace.count());
}

// Forgets the memberships of a client that did not come back (Expiry::Forget).
void forget_away(HandlerState& s, const std::string& client) {
  s.sessions.forget_member(client);
  s.away.erase(client);
  logger()->info("client {} did not come back within {} ms: its memberships are forgotten", client,
                 s.config.session_grace.count());
}

}  // namespace

std::vector<std::string> Handler::expire_leases(std::vector<UpdateEvent>& updates, std::vector<Expiry>* applied) {
  HandlerState& s = *state_;
  const LeaseClock::time_point now = LeaseClock::now();
  auto note = [&](Expiry::Kind kind, const std::string& name) {
    if (applied) applied->push_back({kind, name});
  };
  const std::vector<std::string> expired = s.clients.expired(now, s.config.client_lease);
  for (const std::string& client : expired) {
    detach_client(s, client, now, updates);
    note(Expiry::Kind::Lease, client);
  }
  // Grace periods that ran out: sessions nobody came back to, memberships of clients that did not return.
  for (const std::string& name : s.sessions.names()) {
    const SessionEntry& entry = *s.sessions.find(name);
    if (!entry.clients.empty() || !entry.orphaned_since || now - *entry.orphaned_since < s.config.session_grace) {
      continue;
    }
    drop_orphan(s, name, updates);
    note(Expiry::Kind::Grace, name);
  }
  std::vector<std::string> gone;
  for (const auto& [client, since] : s.away) {
    if (now - since >= s.config.session_grace) gone.push_back(client);
  }
  for (const std::string& client : gone) {
    forget_away(s, client);
    note(Expiry::Kind::Forget, client);
  }
  return expired;
}

void Handler::apply_expiry(const Expiry& expiry, std::vector<UpdateEvent>& updates) {
  HandlerState& s = *state_;
  switch (expiry.kind) {
    case Expiry::Kind::Lease:
      detach_client(s, expiry.name, LeaseClock::now(), updates);
      return;
    case Expiry::Kind::Grace:
      drop_orphan(s, expiry.name, updates);
      return;
    case Expiry::Kind::Forget:
      forget_away(s, expiry.name);
      return;
  }
}

void Handler::start_recovered_leases(std::chrono::milliseconds rejoin) {
  HandlerState& s = *state_;
  // The registry's leases run `client_lease` from when the writer was gone: date that back (or ahead)
  // so that these end `rejoin` from now.
  const auto gone_since = LeaseClock::now() + rejoin - s.config.client_lease;
  for (const std::string& name : s.sessions.names()) {
    for (const std::string& client : s.sessions.find(name)->clients) s.clients.recovered(client, gone_since);
  }
}

std::optional<std::chrono::milliseconds> Handler::next_lease_check() const {
  const HandlerState& s = *state_;
  std::optional<LeaseClock::time_point> next = s.clients.next_expiry(s.config.client_lease);
  auto consider = [&](LeaseClock::time_point t) {
    if (!next || t < *next) next = t;
  };
  for (const auto& [name, entry] : s.sessions.all()) {
    if (entry.clients.empty() && entry.orphaned_since) consider(*entry.orphaned_since + s.config.session_grace);
  }
  for (const auto& [client, since] : s.away) consider(since + s.config.session_grace);
  if (!next) return std::nullopt;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(*next - LeaseClock::now());
  return std::max(left, std::chrono::milliseconds(0));
}

}  // namespace surfeledit::service
