// Clients: role checks, OP_INVITE, and leases (detaching clients whose request writer is gone).
#include "handler_ops.hpp"
#include "surfeledit/service/log.hpp"

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
  c.reply.token = c.state.sessions.invite(*c.entry, role);
  logger()->info("client {} invited a {} to session '{}'", c.command.client_id, role_name(role), c.command.session);
}

void Handler::writer_lost(std::uint64_t sender) { state_->clients.writer_lost(sender, LeaseClock::now()); }

void Handler::writer_alive(std::uint64_t sender) { state_->clients.writer_alive(sender); }

std::vector<std::string> Handler::expire_leases(std::vector<UpdateEvent>& updates) {
  HandlerState& s = *state_;
  const std::vector<std::string> expired = s.clients.expired(LeaseClock::now(), s.config.client_lease);
  for (const std::string& client : expired) {
    const std::uint64_t held = s.uploads.client_bytes(client);
    const std::vector<std::string> sessions = s.sessions.attached_to(client);
    for (const std::string& name : sessions) {
      SessionEntry* entry = s.sessions.find(name);
      const std::uint64_t version = entry->session->version();
      const bool dropped = s.sessions.close(name, client);
      if (!dropped && entry->session->version() != version) {
        updates.push_back(make_update_event(name, entry->session->version(), "release"));  // its tool was released
      }
      if (dropped) {
        s.uploads.erase_session(name);
        updates.push_back(make_update_event(name, version + 1, "close"));
        logger()->info("session '{}' dropped: its last client {} was detached", name, client);
      }
    }
    s.uploads.erase_client(client);
    s.cache.forget(client);
    s.sessions.forget_member(client);
    s.clients.forget(client);
    logger()->info("client {} detached: its request writer was gone for {} ms ({} session(s) closed, {} upload "
                   "bytes freed)",
                   client, s.config.client_lease.count(), sessions.size(), held);
  }
  return expired;
}

std::optional<std::chrono::milliseconds> Handler::next_lease_check() const {
  const auto next = state_->clients.next_expiry(state_->config.client_lease);
  if (!next) return std::nullopt;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(*next - LeaseClock::now());
  return std::max(left, std::chrono::milliseconds(0));
}

}  // namespace surfeledit::service
