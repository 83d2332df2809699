#include "surfeledit/service/handler.hpp"

#include <cctype>
#include <new>
#include <stdexcept>

#include "handler_ops.hpp"
#include "surfeledit/core/util.hpp"
#include "surfeledit/service/log.hpp"
#include "surfeledit/service/protocol_errors.hpp"

namespace surfeledit::service {

namespace {

using Clock = std::chrono::steady_clock;

// The op table, built once: row i serves op i.
std::array<OpEntry, kOpCount> make_op_table() {
  std::array<OpEntry, kOpCount> t{};
  auto row = [&](Op op, OpEntry entry) { t[static_cast<std::size_t>(op)] = entry; };
  using T = ReplyTail;
  //  op                  name                serve                attached  tail                      cached
  row(Op::Info, {"OP_INFO", serve_info, false, T::VersionAndSessionInfo, true});
  row(Op::OpenSession, {"OP_OPEN_SESSION", serve_open_session, false, T::VersionAndSessionInfo, true});
  row(Op::JoinSession, {"OP_JOIN_SESSION", serve_join_session, false, T::VersionAndSessionInfo, true});
  row(Op::CloseSession, {"OP_CLOSE_SESSION", serve_close_session, true, T::Version, true});
  row(Op::LoadBegin, {"OP_LOAD_BEGIN", serve_load_begin, true, T::Version, true});
  row(Op::LoadChunk, {"OP_LOAD_CHUNK", serve_load_chunk, true, T::Version, true});
  row(Op::LoadCommit, {"OP_LOAD_COMMIT", serve_load_commit, true, T::VersionAndSessionInfo, true});
  row(Op::LoadFile, {"OP_LOAD_FILE", serve_load_file, true, T::VersionAndSessionInfo, true});
  row(Op::SetRegions, {"OP_SET_REGIONS", serve_set_regions, true, T::VersionAndSessionInfo, true});
  row(Op::Deform, {"OP_DEFORM", serve_deform, true, T::Version, true});
  row(Op::GetState, {"OP_GET_STATE", serve_get_state, true, T::Version, false});
  row(Op::Configure, {"OP_CONFIGURE", serve_configure, true, T::VersionAndSessionInfo, true});
  row(Op::Remove, {"OP_REMOVE", serve_remove, true, T::VersionAndSessionInfo, true});
  row(Op::Undo, {"OP_UNDO", serve_undo, true, T::VersionAndSessionInfo, true});
  row(Op::Redo, {"OP_REDO", serve_redo, true, T::VersionAndSessionInfo, true});
  row(Op::History, {"OP_HISTORY", serve_history, true, T::Version, false});
  row(Op::Merge, {"OP_MERGE", serve_merge, true, T::VersionAndSessionInfo, true});
  row(Op::Curves, {"OP_CURVES", serve_curves, true, T::Version, false});
  row(Op::Invite, {"OP_INVITE", serve_invite, true, T::Version, true});
  row(Op::Blend, {"OP_BLEND", serve_blend, true, T::VersionAndSessionInfo, true});
  row(Op::Boolean, {"OP_BOOLEAN", serve_boolean, true, T::VersionAndSessionInfo, true});
  row(Op::FillHoles, {"OP_FILL_HOLES", serve_fill_holes, true, T::VersionAndSessionInfo, true});
  row(Op::Peers, {"OP_PEERS", serve_peers, true, T::Version, false});
  row(Op::Release, {"OP_RELEASE", serve_release, true, T::VersionAndSessionInfo, true});
  return t;
}

// Optimistic concurrency: Conflict unless the session is at `expected` (InvalidArgument for a version it
// never reached).
void check_expected_version(const SessionEntry& entry, std::uint64_t expected) {
  const std::uint64_t version = entry.session->version();
  if (expected == version) return;
  if (expected > version) {
    throw Error(ErrorCode::InvalidArgument, "expect_version",
                "expected version " + std::to_string(expected) + " is ahead of the session's version " +
                    std::to_string(version));
  }
  throw Error(ErrorCode::Conflict, "expect_version",
              "the session moved past version " + std::to_string(expected) + ": it is at version " +
                  std::to_string(version));
}

// Names the requesting client as the author of the updates from index `from` on that have none.
void set_author(std::vector<UpdateEvent>& updates, std::size_t from, const std::string& client) {
  for (std::size_t i = from; i < updates.size(); ++i) {
    if (updates[i].author.empty()) updates[i].author = client;
  }
}

// Serves a command whose client id is set: the op's row, its argument, the session, the op. True when
// the op replies later (OpContext::deferred).
bool dispatch(HandlerState& state, const Command& command, Reply& reply, std::vector<UpdateEvent>& updates) {
  const OpEntry* op = find_op(command.op);
  if (!op) {
    throw Error(ErrorCode::InvalidArgument, "op",
                "unknown op " + std::to_string(static_cast<long>(static_cast<std::uint32_t>(command.op))));
  }
  if (command.missing) std::rethrow_exception(command.missing);
  SessionEntry* entry = op->attached ? &state.sessions.attached(command.session, command.client_id) : nullptr;
  if (entry) check_role(*entry, command);
  if (command.invalid) std::rethrow_exception(command.invalid);
  if (entry && command.expect_version && required_role(static_cast<std::uint32_t>(command.op)) >= Role::Editor) {
    check_expected_version(*entry, *command.expect_version);
  }
  const std::uint64_t version_before = entry ? entry->session->version() : 0;
  if (entry) note_activity(*entry, command.client_id, command.op, version_before, Clock::now());  // idle from now
  OpContext context{state, command, entry, reply, updates};
  op->serve(context);
  if (context.entry) {  // open / join: the version the client found
    const std::uint64_t before = entry ? version_before : context.entry->session->version();
    note_activity(*context.entry, command.client_id, command.op, before, Clock::now());
  }
  if (context.deferred) return true;
  if (context.entry) fill_reply_tail(reply, *context.entry, op->tail, command.client_id);
  return false;
}

// The argument an op's failure is charged to when nothing more precise is known (out of memory):
// "OP_LOAD_CHUNK" -> "load_chunk"; "op" for a number outside the table.
std::string argument_of(const std::string& op) {
  if (op.rfind("OP_", 0) != 0 || (op.size() > 3 && std::isdigit(static_cast<unsigned char>(op[3])))) return "op";
  std::string out = op.substr(3);
  for (char& ch : out) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return out;
}

// Runs `body`; whatever it throws becomes the reply's error (status, field, message), nothing is
// published, and the reply's version is the session's (unchanged) current version.
template <typename F>
void run_guarded(HandlerState& state, const std::string& op, const std::string& session, Reply& reply,
                 std::vector<UpdateEvent>& updates, F&& body) {
  const std::size_t updates_before = updates.size();
  auto fail = [&](Status status, std::string field, std::string message) {
    updates.resize(updates_before);  // nothing was changed, so nothing is published
    reply.status = status;
    reply.field = std::move(field);
    reply.message = std::move(message);
    reply.state.reset();
    reply.session_info.reset();
    reply.server_info.reset();
    reply.step.reset();
  };
  try {
    body();
  } catch (const Error& e) {
    fail(status_of(e.code()), e.field(), message_of(e));
  } catch (const PermissionDenied& e) {
    fail(Status::PermissionDenied, e.field(), e.what());
  } catch (const std::bad_alloc&) {
    fail(Status::TooLarge, argument_of(op), "out of memory while serving " + op);
  } catch (const std::exception& e) {
    fail(Status::Internal, "", std::string("internal error: ") + e.what());
  }
  if (reply.status != Status::Ok) {
    // The reply's version is the session's (unchanged) current version
    // (0 for a session the caller is not a member of: a refusal tells nothing about it).
    SessionEntry* entry = state.sessions.find_for(session, reply.client_id);
    reply.version = entry ? entry->session->version() : 0;
    const auto level = reply.status == Status::Internal ? spdlog::level::warn : spdlog::level::info;
    logger()->log(level, "request {}#{} {} session '{}' failed: status {} field '{}': {}", reply.client_id,
                  reply.request_id, op, session, static_cast<unsigned>(reply.status), reply.field, reply.message);
  }
}

}  // namespace

const OpEntry* find_op(Op op) {
  static const std::array<OpEntry, kOpCount> table = make_op_table();
  const auto i = static_cast<std::size_t>(op);
  if (i >= table.size() || !table[i].serve) return nullptr;
  return &table[i];
}

std::string op_name(Op op) {
  if (const OpEntry* entry = find_op(op)) return entry->name;
  return "OP_" + std::to_string(static_cast<std::uint32_t>(op));
}

bool has_handler(Op op) { return find_op(op) != nullptr; }

HandlerState::HandlerState(const HandlerConfig& c)
    : config(c),
      sessions(SessionParams{c.threads}),
      uploads(UploadLimits{c.max_chunk_surfels, c.max_model_surfels, c.max_client_upload_bytes, c.max_upload_bytes}),
      cache(RequestCacheLimits{1024, 4096, static_cast<std::size_t>(c.max_reply_cache_bytes)}),
      started(Clock::now()),
      data_root(c.data_root, c.max_file_bytes) {}

Handler::Handler(HandlerConfig config) : state_(std::make_unique<HandlerState>(config)) {
  if (config.max_chunk_surfels == 0) throw std::invalid_argument("max_chunk_surfels must be positive");
  if (config.max_model_surfels == 0) throw std::invalid_argument("max_model_surfels must be positive");
}

Handler::~Handler() = default;

const HandlerConfig& Handler::config() const { return state_->config; }

const SurfelModel* Handler::model_of(const std::string& session) {
  SessionEntry* entry = state_->sessions.find(session);
  if (!entry || !entry->session->has_model()) return nullptr;
  return &entry->session->model();
}

std::optional<UpdateEvent> Handler::changes_event(const std::string& session, std::uint64_t since) const {
  const SessionEntry* entry = state_->sessions.find(session);
  if (!entry) return std::nullopt;
  return service::changes_event(*entry->session, session, since);
}

std::shared_ptr<const Reply> Handler::handle(const Command& command, std::vector<UpdateEvent>& updates) {
  const Clock::time_point t0 = Clock::now();
  auto reply = std::make_shared<Reply>();
  reply->client_id = command.client_id;
  reply->request_id = command.request_id;
  reply->request_op = static_cast<std::uint32_t>(command.op);
  const std::string& session = command.session;
  const std::string op = op_name(command.op);
  auto log = logger();
  log->debug("request {}#{} {} session '{}'", reply->client_id, reply->request_id, op, session);

  // Identity first: the cache and everything else see only requests of the writer bound to the id.
  if (!reply->client_id.empty() && command.sender != 0 &&
      !state_->clients.admit(reply->client_id, command.sender, t0)) {
    log->warn("request {}#{} {} session '{}' refused without a reply: client id bound to another writer (sender "
              "{:x}), or that writer holds too many ids",
              reply->client_id, reply->request_id, op, session, command.sender);
    return nullptr;
  }
  if (!reply->client_id.empty()) {
    if (state_->loads.pending(reply->client_id, reply->request_id)) {
      log->debug("request {}#{} is a repeat of a load in progress: its reply comes when it finishes",
                 reply->client_id, reply->request_id);
      return nullptr;
    }
    if (auto stored = state_->cache.find(reply->client_id, reply->request_id)) {
      if (stored->request_op == reply->request_op) {
        log->debug("request {}#{} is a repeat: answered with the stored reply", reply->client_id, reply->request_id);
        return stored;
      }
      // Same id, another op: not a repeat; refused without touching the stored reply.
      reply->status = Status::InvalidArgument;
      reply->field = "request_id";
      reply->message = "request id " + std::to_string(reply->request_id) + " was used for " +
                       op_name(static_cast<Op>(stored->request_op)) + "; request ids must be unique per client";
      return reply;
    }
  }

  // A client detached by its lease is back (a restarted process with the same id): its memberships stay.
  if (!reply->client_id.empty()) state_->away.erase(reply->client_id);
  bool deferred = false;
  const std::size_t updates_before = updates.size();
  run_guarded(*state_, op, session, *reply, updates, [&] {
    if (reply->client_id.empty()) throw Error(ErrorCode::InvalidArgument, "client_id", "a client id is required");
    deferred = dispatch(*state_, command, *reply, updates);
  });
  set_author(updates, updates_before, reply->client_id);
  if (deferred) return nullptr;
  reply->timings.emplace_back("total", ms_since(t0));

  // Ops whose row says so (GET_STATE pages, up to max_chunk_surfels surfels each) are not stored:
  // they change nothing, so a repeat is answered by computing the reply again.
  const OpEntry* row = find_op(command.op);
  if (!reply->client_id.empty() && (!row || row->cached)) {
    state_->cache.put(reply);
    if (state_->on_stored) state_->on_stored(*reply);
  }
  return reply;
}

std::vector<std::shared_ptr<const Reply>> Handler::finish_loads(std::vector<UpdateEvent>& updates) {
  std::vector<std::shared_ptr<const Reply>> replies;
  for (FileLoad& load : state_->loads.take_finished()) {
    auto reply = std::make_shared<Reply>();
    reply->client_id = load.client_id;
    reply->request_id = load.request_id;
    reply->request_op = static_cast<std::uint32_t>(Op::LoadFile);
    const std::size_t updates_before = updates.size();
    run_guarded(*state_, "OP_LOAD_FILE", load.session, *reply, updates,
                [&] { finish_load_file(*state_, load, *reply, updates); });
    set_author(updates, updates_before, load.client_id);
    reply->timings.emplace_back("total", ms_since(load.started));
    state_->cache.put(reply);
    if (state_->on_stored) state_->on_stored(*reply);
    replies.push_back(std::move(reply));
  }
  return replies;
}

void Handler::set_on_stored(std::function<void(const Reply&)> on_stored) { state_->on_stored = std::move(on_stored); }

void Handler::remember(const Reply& reply) { state_->cache.put(std::make_shared<const Reply>(reply)); }

void Handler::set_next_token(std::string token) { state_->next_token = std::move(token); }

void Handler::set_on_load_done(std::function<void()> on_done) { state_->loads.set_on_done(std::move(on_done)); }

void fill_reply_tail(Reply& reply, const SessionEntry& entry, ReplyTail tail, const std::string& client) {
  reply.version = entry.session->version();
  if (tail == ReplyTail::VersionAndSessionInfo) reply.session_info = session_info(entry, client);
}

}  // namespace surfeledit::service
