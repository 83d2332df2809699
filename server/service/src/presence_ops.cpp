// Presence (PROTOCOL.md, "Peers and presence"): who is in a session, as what, what it did last and
// the size of its tool; OP_PEERS; the "presence" updates of joins, leaves, lease expiries and region
// changes; and the two hooks a client's tool hangs off (its summary, its release).
#include <algorithm>
#include <cctype>

#include "handler_ops.hpp"

namespace surfeledit::service {

ToolSummary tool_summary(const SessionEntry& entry, const std::string& client) {
  ToolSummary out;
  const DeformationFields* fields = entry.session->fields(client);
  if (!fields) return out;
  for (Region r : fields->regions) {
    if (r == Region::Zero) ++out.zero;
    if (r == Region::One) ++out.one;
  }
  out.deformable = static_cast<std::uint64_t>(fields->deformable.size());
  return out;
}

void release_tool(SessionEntry& entry, const std::string& session, const std::string& client,
                  std::vector<UpdateEvent>& updates) {
  EditSession& s = *entry.session;
  if (!s.release(client)) return;  // a tool without regions holds no lock: nothing changes
  UpdateEvent event = make_update_event(session, s.version(), "release");
  event.author = client;
  updates.push_back(std::move(event));
}

void note_activity(SessionEntry& entry, const std::string& client, Op op, std::uint64_t version_before,
                   std::chrono::steady_clock::time_point now) {
  if (!entry.role_of(client)) return;  // not a member (any more): nothing to show
  PeerActivity& a = entry.activity[client];
  a.last_request = now;
  const std::uint64_t version = entry.session->version();
  if (version == version_before) return;
  std::string name = op_name(op);
  if (name.rfind("OP_", 0) == 0) name.erase(0, 3);
  for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  a.last_op = std::move(name);
  a.last_version = version;
}

std::vector<PeerInfo> peers_of(const HandlerState& state, const SessionEntry& entry,
                               std::chrono::steady_clock::time_point now) {
  auto ms = [&](std::chrono::steady_clock::time_point t) {
    return std::max(0.0, std::chrono::duration<double, std::milli>(now - t).count());
  };
  std::vector<PeerInfo> out;
  for (const auto& [client, role] : entry.members) {
    PeerInfo p;
    p.client_id = client;
    p.role = role_name(role);
    const auto away = state.away.find(client);
    if (entry.clients.count(client)) {
      const ClientRecord* record = state.clients.find(client);
      p.state = record && record->gone_since ? "lease" : "attached";
    } else if (away != state.away.end()) {
      p.state = "away";
    } else {
      continue;  // a member that is not attached (closed the session, or never opened it)
    }
    const auto act = entry.activity.find(client);
    if (act != entry.activity.end()) {
      p.last_op = act->second.last_op;
      p.last_version = act->second.last_version;
    }
    if (p.state == "away") {
      p.idle_ms = ms(away->second);
    } else if (act != entry.activity.end()) {
      p.idle_ms = ms(act->second.last_request);
    }
    const ToolSummary tool = tool_summary(entry, client);
    p.zero = tool.zero;
    p.one = tool.one;
    p.deformable = tool.deformable;
    out.push_back(std::move(p));
  }
  return out;
}

UpdateEvent presence_event(const HandlerState& state, const SessionEntry& entry, const std::string& session,
                           const std::string& client, const char* what) {
  UpdateEvent event = make_update_event(session, entry.session->version(), "presence");
  event.author = client;
  event.presence = what;
  event.peers = peers_of(state, entry, std::chrono::steady_clock::now());
  return event;
}

void serve_peers(OpContext& c) { c.reply.peers = peers_of(c.state, *c.entry, std::chrono::steady_clock::now()); }

}  // namespace surfeledit::service
