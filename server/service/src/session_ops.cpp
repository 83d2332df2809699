// Handler functions of the session ops: INFO, OPEN_SESSION, JOIN_SESSION, CLOSE_SESSION.
#include <algorithm>

#include "handler_ops.hpp"
#include "surfeledit/service/log.hpp"
#include "surfeledit/service/reply_values.hpp"

#ifndef SURFELEDIT_VERSION
#define SURFELEDIT_VERSION "unknown"
#endif

namespace surfeledit::service {

SessionInfo session_info(const SessionEntry& entry, const std::string& client) {
  const EditSession& s = *entry.session;
  SessionInfo info;
  info.name = s.name();
  info.has_regions = !s.tools().empty();  // some client's tool has regions (the settings are the caller's)
  info.clients = static_cast<std::uint32_t>(entry.clients.size());
  if (s.has_model()) {
    info.surfels = static_cast<std::uint64_t>(s.model().size());
    info.state_hash = s.state_hash();
    const SessionReport report = s.report();
    info.bytes_per_surfel = report.bytes_per_surfel;
    for (const StructureInfo& st : report.structures) info.structures.emplace_back(st.name, st.bytes);
  }
  for (const NamedSetting& setting : describe(s.settings(client))) info.settings.push_back(to_reply(setting));
  return info;
}

void serve_info(OpContext& c) {
  const HandlerState& state = c.state;
  ServerInfo info;
  info.version = SURFELEDIT_VERSION;
  info.uptime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - state.started).count();
  // Only the sessions the caller is a member of; others' are neither listed nor described.
  info.sessions = state.sessions.names_for(c.command.client_id);
  info.max_chunk_surfels = state.config.max_chunk_surfels;
  info.max_model_surfels = state.config.max_model_surfels;
  info.clients = static_cast<std::uint32_t>(state.clients.size());
  info.upload_bytes = state.uploads.bytes();
  info.client_upload_bytes = state.uploads.client_bytes(c.command.client_id);
  info.max_upload_bytes = state.config.max_upload_bytes;
  info.max_client_upload_bytes = state.config.max_client_upload_bytes;
  info.reply_cache_bytes = state.cache.bytes();
  info.client_lease_s = std::chrono::duration<double>(state.config.client_lease).count();
  info.session_grace_s = std::chrono::duration<double>(state.config.session_grace).count();
  c.reply.server_info = std::move(info);
  // The session, when named and the caller is a member, for the reply tail.
  c.entry = c.command.session.empty() ? nullptr : c.state.sessions.find_for(c.command.session, c.command.client_id);
}

namespace {

// Whether `client` is attached to the session named `name` (which may not exist).
bool is_attached(const HandlerState& state, const std::string& name, const std::string& client) {
  const SessionEntry* entry = state.sessions.find(name);
  return entry && entry->clients.count(client) > 0;
}

// After an open or a join: a "presence" update when the client was not attached before.
void announce_join(OpContext& c, bool was_attached) {
  if (was_attached) return;
  c.updates.push_back(presence_event(c.state, *c.entry, c.command.session, c.command.client_id, "join"));
}

}  // namespace

void serve_open_session(OpContext& c) {
  const bool was_attached = is_attached(c.state, c.command.session, c.command.client_id);
  c.entry = &c.state.sessions.open(c.command.session, c.command.client_id);
  announce_join(c, was_attached);
}

void serve_join_session(OpContext& c) {
  const bool was_attached = is_attached(c.state, c.command.session, c.command.client_id);
  c.entry = &c.state.sessions.join(c.command.session, c.command.client_id, c.command.token,
                                   granted_role(c.state.config.grants, c.command.subject, c.command.session));
  announce_join(c, was_attached);
}

void serve_close_session(OpContext& c) {
  const std::string& session = c.command.session;
  const std::string& client = c.command.client_id;
  c.state.uploads.erase(client, session);
  release_tool(*c.entry, session, client, c.updates);
  const std::uint64_t version = c.entry->session->version();
  // A member detached by its lease may still come back: the session then waits for it (grace period).
  const bool awaited = std::any_of(c.entry->members.begin(), c.entry->members.end(), [&](const auto& member) {
    return member.first != client && c.state.away.count(member.first) > 0;
  });
  if (!awaited && c.state.sessions.close(session, client)) {
    c.entry = nullptr;  // dropped: the reply tail has no session to describe
    c.state.uploads.erase_session(session);
    c.updates.push_back(make_update_event(session, version + 1, "close"));
    c.reply.version = version + 1;
    logger()->info("session '{}' dropped: its last client {} closed it", session, client);
    return;
  }
  if (awaited && c.state.sessions.leave(session, client)) {
    c.entry->orphaned_since = std::chrono::steady_clock::now();
    logger()->info("session '{}' kept for {} ms: its last client {} closed it while a member is away", session,
                   c.state.config.session_grace.count(), client);
  }
  c.updates.push_back(presence_event(c.state, *c.entry, session, client, "leave"));
}

}  // namespace surfeledit::service
