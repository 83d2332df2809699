// The handler's op table (FCL's collision function matrix is the model): one row per op with
// its handler function and what Handler::handle does around it. A handler function serves a
// decoded Command whose argument is present and valid and whose client is attached when its row
// says so; it throws surfeledit::Error for what it rejects, before changing anything.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "surfeledit/service/client_registry.hpp"
#include "surfeledit/service/command.hpp"
#include "surfeledit/service/handler.hpp"
#include "surfeledit/service/protocol_errors.hpp"
#include "surfeledit/service/reply.hpp"
#include "surfeledit/service/request_cache.hpp"
#include "surfeledit/service/session_registry.hpp"
#include "surfeledit/service/update.hpp"
#include "surfeledit/service/upload.hpp"
#include "data_root.hpp"
#include "file_loads.hpp"

namespace surfeledit::service {

// What the handler keeps between requests.
struct HandlerState {
  explicit HandlerState(const HandlerConfig& c);

  HandlerConfig config;
  SessionRegistry sessions;
  UploadTable uploads;        // uploads in progress
  RequestCache cache;         // replies for repeated request ids
  ClientRegistry clients;     // client id -> the writer it is bound to, activity, lease
  std::chrono::steady_clock::time_point started;  // for the uptime
  DataRoot data_root;         // where OP_LOAD_FILE may read
  FileLoads loads;            // OP_LOAD_FILE loads running off the request thread
  std::function<void(const Reply&)> on_stored;  // the journal: a reply was stored (Handler::set_on_stored)
  std::string next_token;     // replay: the token the next OP_INVITE hands out (empty: a fresh one)
  // Clients detached by their lease -> when: their memberships are kept for config.session_grace (a
  // restarted client with the same id finds its sessions and role), then forgotten.
  std::map<std::string, LeaseClock::time_point> away;
};

// One request being served.
struct OpContext {
  HandlerState& state;
  const Command& command;
  SessionEntry* entry;                // the session the reply tail describes; nullptr: none (set by the op
                                      // for ops that attach the client themselves, cleared when it is dropped)
  Reply& reply;
  std::vector<UpdateEvent>& updates;  // appended: the changes to publish
  bool deferred = false;              // set by an op that replies later (OP_LOAD_FILE: Handler::finish_loads)
};

using OpHandler = void (*)(OpContext&);

// What the reply tail (fill_reply_tail) adds after the handler function returned.
enum class ReplyTail {
  Version,                // the session's version
  VersionAndSessionInfo,  // and its SessionInfo
};

// One row of the op table.
struct OpEntry {
  const char* name = nullptr;           // for logs: "OP_DEFORM"
  OpHandler serve = nullptr;            // nullptr: no such op
  bool attached = true;                 // the client must be attached to the session before `serve`
  ReplyTail tail = ReplyTail::Version;  // added when the context still has a session afterwards
  bool cached = true;                   // stored for repeats (false: recomputed, e.g. GET_STATE pages)
};

// The row of `op`, or nullptr for a value outside the table.
const OpEntry* find_op(Op op);

// The reply tail: the session's version, and its SessionInfo (as `client` sees it) when `tail` says so.
void fill_reply_tail(Reply& reply, const SessionEntry& entry, ReplyTail tail, const std::string& client);

// Refuses (PermissionDenied) a command whose op needs a stronger role in the session than the
// client has (client_ops.cpp).
void check_role(const SessionEntry& entry, const Command& command);

// The session's description for replies to `client` (session_ops.cpp): the settings are those of the
// client's tool; has_regions: some tool has regions.
SessionInfo session_info(const SessionEntry& entry, const std::string& client);

// Presence (presence_ops.cpp).
// The sizes of a client's tool in the session: its zero, one and deformable (s > 0) regions.
struct ToolSummary {
  std::uint64_t zero = 0;        // surfels of the zero region
  std::uint64_t one = 0;         // surfels of the one region
  std::uint64_t deformable = 0;  // surfels it may move (the one region and the band between)
};
// `client`'s tool in the session (EditSession::fields of its tool; zeros when it has no regions).
ToolSummary tool_summary(const SessionEntry& entry, const std::string& client);
// Frees `client`'s tool in the session (its regions, detector and lock: EditSession::release) when it
// leaves the session or its lease ends, before it is detached; appends a "release" update to `updates`
// when that changed the session (the tool held regions).
void release_tool(SessionEntry& entry, const std::string& session, const std::string& client,
                  std::vector<UpdateEvent>& updates);
// Records a served request of `client` (its time; op and version when it changed the version).
void note_activity(SessionEntry& entry, const std::string& client, Op op, std::uint64_t version_before,
                   std::chrono::steady_clock::time_point now);
// The session's attached clients and away members (detached by lease, within the grace period), by id.
std::vector<PeerInfo> peers_of(const HandlerState& state, const SessionEntry& entry,
                               std::chrono::steady_clock::time_point now);
// A "presence" update of the session at its current version: `what` happened to `client`, with every peer.
UpdateEvent presence_event(const HandlerState& state, const SessionEntry& entry, const std::string& session,
                           const std::string& client, const char* what);

// Handler functions, one per op: session_ops.cpp, load_ops.cpp, edit_ops.cpp, state_ops.cpp.
void serve_info(OpContext& c);
void serve_open_session(OpContext& c);
void serve_join_session(OpContext& c);
void serve_close_session(OpContext& c);
void serve_load_begin(OpContext& c);
void serve_load_chunk(OpContext& c);
void serve_load_commit(OpContext& c);
void serve_load_file(OpContext& c);
void serve_set_regions(OpContext& c);
void serve_deform(OpContext& c);
void serve_get_state(OpContext& c);
void serve_configure(OpContext& c);
void serve_remove(OpContext& c);
void serve_undo(OpContext& c);
void serve_redo(OpContext& c);
void serve_history(OpContext& c);
void serve_merge(OpContext& c);
void serve_curves(OpContext& c);
// The second half of OP_LOAD_FILE, on the request thread once the file was read (load_ops.cpp): commits
// the model into the session (the client must still be attached) and fills the reply.
void finish_load_file(HandlerState& state, FileLoad& load, Reply& reply, std::vector<UpdateEvent>& updates);
void serve_invite(OpContext& c);
// blend_ops.cpp
void serve_blend(OpContext& c);
void serve_boolean(OpContext& c);
void serve_fill_holes(OpContext& c);
// presence_ops.cpp
void serve_peers(OpContext& c);
// tool_ops.cpp
void serve_release(OpContext& c);

// The op's argument (the Command's variant holds it once find_op's row is served).
template <typename Args>
const Args& args_of(const OpContext& c) {
  return std::get<Args>(c.command.args);
}

// Runs `f`, re-throwing core errors with their field under `prefix` (see rethrow_prefixed).
template <typename F>
auto prefixed(const std::string& prefix, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const Error& e) {
    rethrow_prefixed(e, prefix);
  }
}

}  // namespace surfeledit::service
