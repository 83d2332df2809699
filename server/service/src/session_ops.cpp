// Handler functions of the session ops: INFO, OPEN_SESSION, JOIN_SESSION, CLOSE_SESSION.
#include "handler_ops.hpp"
#include "surfeledit/service/log.hpp"

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
  c.reply.server_info = std::move(info);
  // The session, when named and the caller is a member, for the reply tail.
  c.entry = c.command.session.empty() ? nullptr : c.state.sessions.find_for(c.command.session, c.command.client_id);
}

void serve_open_session(OpContext& c) { c.entry = &c.state.sessions.open(c.command.session, c.command.client_id); }

void serve_join_session(OpContext& c) {
  c.entry = &c.state.sessions.join(c.command.session, c.command.client_id, c.command.token);
}

void serve_close_session(OpContext& c) {
  const std::string& session = c.command.session;
  const std::string& client = c.command.client_id;
  const std::uint64_t version = c.entry->session->version();
  c.state.uploads.erase(client, session);
  const bool dropped = c.state.sessions.close(session, client);
  if (!dropped && c.entry->session->version() != version) {
    c.updates.push_back(make_update_event(session, c.entry->session->version(), "release"));
  }
  if (dropped) {
    c.entry = nullptr;  // dropped: the reply tail has no session to describe
    c.state.uploads.erase_session(session);
    c.updates.push_back(make_update_event(session, version + 1, "close"));
    c.reply.version = version + 1;
    logger()->info("session '{}' dropped: its last client {} closed it", session, client);
  }
}

}  // namespace surfeledit::service
