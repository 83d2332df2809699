#include "surfeledit/service/handler.hpp"

#include <new>
#include <stdexcept>

#include "handler_ops.hpp"
#include "surfeledit/core/util.hpp"
#include "surfeledit/service/log.hpp"

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
  row(Op::Blend, {"OP_BLEND", serve_blend, true, T::VersionAndSessionInfo, true});
  row(Op::Boolean, {"OP_BOOLEAN", serve_boolean, true, T::VersionAndSessionInfo, true});
  row(Op::FillHoles, {"OP_FILL_HOLES", serve_fill_holes, true, T::VersionAndSessionInfo, true});
  return t;
}

// Serves a command whose client id is set: the op's row, its argument, the session, the op.
void dispatch(HandlerState& state, const Command& command, Reply& reply, std::vector<UpdateEvent>& updates) {
  const OpEntry* op = find_op(command.op);
  if (!op) {
    throw Error(ErrorCode::InvalidArgument, "op",
                "unknown op " + std::to_string(static_cast<long>(static_cast<std::uint32_t>(command.op))));
  }
  if (command.missing) std::rethrow_exception(command.missing);
  SessionEntry* entry = op->attached ? &state.sessions.attached(command.session, command.client_id) : nullptr;
  if (command.invalid) std::rethrow_exception(command.invalid);
  OpContext context{state, command, entry, reply, updates};
  op->serve(context);
  if (context.entry) fill_reply_tail(reply, *context.entry, op->tail);
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
      uploads(UploadLimits{c.max_chunk_surfels, c.max_model_surfels}),
      started(Clock::now()) {}

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
  const std::string& session = command.session;
  const std::string op = op_name(command.op);
  auto log = logger();
  log->debug("request {}#{} {} session '{}'", reply->client_id, reply->request_id, op, session);

  if (!reply->client_id.empty()) {
    if (auto stored = state_->cache.find(reply->client_id, reply->request_id)) {
      log->debug("request {}#{} is a repeat: answered with the stored reply", reply->client_id, reply->request_id);
      return stored;
    }
  }

  const std::size_t updates_before = updates.size();
  auto fail = [&](Status status, std::string field, std::string message) {
    updates.resize(updates_before);  // nothing was changed, so nothing is published
    reply->status = status;
    reply->field = std::move(field);
    reply->message = std::move(message);
    reply->state.reset();
    reply->session_info.reset();
    reply->server_info.reset();
    reply->step.reset();
  };
  try {
    if (reply->client_id.empty()) throw Error(ErrorCode::InvalidArgument, "client_id", "a client id is required");
    dispatch(*state_, command, *reply, updates);
  } catch (const Error& e) {
    fail(status_of(e.code()), e.field(), message_of(e));
  } catch (const std::bad_alloc&) {
    fail(Status::TooLarge, "", "out of memory while serving " + op);
  } catch (const std::exception& e) {
    fail(Status::Internal, "", std::string("internal error: ") + e.what());
  }

  if (reply->status != Status::Ok) {
    // The reply's version is the session's (unchanged) current version.
    SessionEntry* entry = state_->sessions.find(session);
    reply->version = entry ? entry->session->version() : 0;
    const auto level = reply->status == Status::Internal ? spdlog::level::warn : spdlog::level::info;
    log->log(level, "request {}#{} {} session '{}' failed: status {} field '{}': {}", reply->client_id,
             reply->request_id, op, session, static_cast<unsigned>(reply->status), reply->field, reply->message);
  }
  reply->timings.emplace_back("total", ms_since(t0));

  // Ops whose row says so (GET_STATE pages, up to max_chunk_surfels surfels each) are not stored:
  // they change nothing, so a repeat is answered by computing the reply again.
  const OpEntry* row = find_op(command.op);
  if (!reply->client_id.empty() && (!row || row->cached)) state_->cache.put(reply);
  return reply;
}

void fill_reply_tail(Reply& reply, const SessionEntry& entry, ReplyTail tail) {
  reply.version = entry.session->version();
  if (tail == ReplyTail::VersionAndSessionInfo) reply.session_info = session_info(entry);
}

}  // namespace surfeledit::service
