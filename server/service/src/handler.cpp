#include "surfeledit/service/handler.hpp"

#include <algorithm>
#include <new>

#include "surfeledit/core/model_io.hpp"
#include "surfeledit/core/util.hpp"
#include "surfeledit/service/convert.hpp"
#include "surfeledit/service/log.hpp"

#ifndef SURFELEDIT_VERSION
#define SURFELEDIT_VERSION "unknown"
#endif

namespace surfeledit::service {

namespace {

using Clock = std::chrono::steady_clock;

// The one element of an op's argument sequence; InvalidArgument naming the sequence otherwise.
template <typename Seq>
const auto& the_argument(const Seq& seq, const char* name) {
  if (seq._length != 1 || seq._buffer == nullptr) {
    throw Error(ErrorCode::InvalidArgument, name,
                std::string("expected exactly one element, got ") + std::to_string(seq._length));
  }
  return seq._buffer[0];
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

}  // namespace

std::string op_name(int op) {
  static const char* const names[] = {"OP_INFO",       "OP_OPEN_SESSION", "OP_JOIN_SESSION", "OP_CLOSE_SESSION",
                                      "OP_LOAD_BEGIN", "OP_LOAD_CHUNK",   "OP_LOAD_COMMIT",  "OP_LOAD_FILE",
                                      "OP_SET_REGIONS", "OP_DEFORM",      "OP_GET_STATE",    "OP_CONFIGURE",
                                      "OP_REMOVE"};
  if (op >= 0 && op < static_cast<int>(sizeof(names) / sizeof(names[0]))) return names[op];
  return "OP_" + std::to_string(op);
}

Handler::Handler(HandlerConfig config)
    : config_(config),
      sessions_(SessionParams{config.threads}),
      uploads_(UploadLimits{config.max_chunk_surfels, config.max_model_surfels}),
      started_(Clock::now()) {
  if (config_.max_chunk_surfels == 0) throw std::invalid_argument("max_chunk_surfels must be positive");
  if (config_.max_model_surfels == 0) throw std::invalid_argument("max_model_surfels must be positive");
}

const SurfelModel* Handler::model_of(const std::string& session) {
  SessionEntry* entry = sessions_.find(session);
  if (!entry || !entry->session->has_model()) return nullptr;
  return &entry->session->model();
}

std::shared_ptr<const Reply> Handler::handle(const surfeledit_proto_Request& request,
                                             std::vector<UpdateEvent>& updates) {
  const Clock::time_point t0 = Clock::now();
  auto reply = std::make_shared<Reply>();
  reply->client_id = str(request.client_id);
  reply->request_id = request.request_id;
  const std::string session = str(request.session);
  const int op = static_cast<int>(request.op);
  auto log = logger();
  log->debug("request {}#{} {} session '{}'", reply->client_id, reply->request_id, op_name(op), session);

  if (!reply->client_id.empty()) {
    if (auto stored = cache_.find(reply->client_id, reply->request_id)) {
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
    dispatch(request, *reply, updates);
  } catch (const Error& e) {
    fail(status_of(e.code()), e.field(), message_of(e));
  } catch (const std::bad_alloc&) {
    fail(Status::TooLarge, "", "out of memory while serving " + op_name(op));
  } catch (const std::exception& e) {
    fail(Status::Internal, "", std::string("internal error: ") + e.what());
  }

  if (reply->status != Status::Ok) {
    // The reply's version is the session's (unchanged) current version.
    SessionEntry* entry = sessions_.find(session);
    reply->version = entry ? entry->session->version() : 0;
    const auto level = reply->status == Status::Internal ? spdlog::level::warn : spdlog::level::info;
    log->log(level, "request {}#{} {} session '{}' failed: status {} field '{}': {}", reply->client_id,
             reply->request_id, op_name(op), session, static_cast<unsigned>(reply->status), reply->field,
             reply->message);
  }
  reply->timings.emplace_back("total", ms_since(t0));

  // GET_STATE pages (up to max_chunk_surfels surfels each) are not stored: they change
  // nothing, so a repeat is answered by computing the page again.
  if (!reply->client_id.empty() && request.op != surfeledit_proto_OP_GET_STATE) cache_.put(reply);
  return reply;
}

void Handler::dispatch(const surfeledit_proto_Request& request, Reply& reply, std::vector<UpdateEvent>& updates) {
  const std::string& client = reply.client_id;
  const std::string session = str(request.session);

  switch (request.op) {
    case surfeledit_proto_OP_INFO: {
      reply.server_info = server_info();
      if (SessionEntry* entry = session.empty() ? nullptr : sessions_.find(session)) {
        reply.session_info = session_info(*entry);
        reply.version = entry->session->version();
      }
      return;
    }
    case surfeledit_proto_OP_OPEN_SESSION: {
      SessionEntry& entry = sessions_.open(session, client);
      reply.session_info = session_info(entry);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_JOIN_SESSION: {
      SessionEntry& entry = sessions_.join(session, client);
      reply.session_info = session_info(entry);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_CLOSE_SESSION: {
      const std::uint64_t version = sessions_.attached(session, client).session->version();
      uploads_.erase(client, session);
      if (sessions_.close(session, client)) {
        uploads_.erase_session(session);
        UpdateEvent event;
        event.session = session;
        event.version = version + 1;
        event.cause = "close";
        updates.push_back(std::move(event));
        reply.version = version + 1;
        logger()->info("session '{}' dropped: its last client {} closed it", session, client);
      } else {
        reply.version = version;
      }
      return;
    }
    case surfeledit_proto_OP_LOAD_BEGIN: {
      const auto& args = the_argument(request.load_begin, "load_begin");
      SessionEntry& entry = sessions_.attached(session, client);
      uploads_.begin(client, session, args.total, args.has_radii);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_LOAD_CHUNK: {
      const auto& args = the_argument(request.load_chunk, "load_chunk");
      SessionEntry& entry = sessions_.attached(session, client);
      Upload* upload = uploads_.find(client, session);
      if (!upload) throw Error(ErrorCode::Conflict, "load_chunk", "no upload in progress: send OP_LOAD_BEGIN first");
      ChunkData chunk;
      chunk.offset = args.offset;
      chunk.positions = args.positions._buffer;
      chunk.positions_len = args.positions._length;
      chunk.normals = args.normals._buffer;
      chunk.normals_len = args.normals._length;
      chunk.radii = args.radii._buffer;
      chunk.radii_len = args.radii._length;
      upload->add_chunk(chunk);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_LOAD_COMMIT: {
      SessionEntry& entry = sessions_.attached(session, client);
      Upload* upload = uploads_.find(client, session);
      if (!upload) throw Error(ErrorCode::Conflict, "op", "no upload in progress: send OP_LOAD_BEGIN first");
      if (!upload->complete()) {
        throw Error(ErrorCode::Conflict, "load_begin.total",
                    "upload incomplete: received " + std::to_string(upload->received()) + " of " +
                        std::to_string(upload->total()) + " surfels");
      }
      prefixed("load_chunk", [&] { validate_arrays(upload->arrays()); });
      SurfelArrays arrays = upload->take();
      uploads_.erase(client, session);
      SurfelModel model = prefixed("load_chunk", [&] { return SurfelModel::from_arrays(std::move(arrays)); });
      replace_model(entry, session, std::move(model), reply, updates);
      return;
    }
    case surfeledit_proto_OP_LOAD_FILE: {
      const auto& args = the_argument(request.load_file, "load_file");
      SessionEntry& entry = sessions_.attached(session, client);
      const std::string path = str(args.path);
      if (path.empty()) throw Error(ErrorCode::InvalidArgument, "load_file.path", "a file path is required");
      SurfelArrays arrays = prefixed("load_file", [&] { return load_surfels(path); });
      const auto rows = static_cast<std::uint64_t>(arrays.positions.rows());
      if (rows > config_.max_model_surfels) {
        throw Error(ErrorCode::TooLarge, "load_file.path",
                    "'" + path + "' holds " + std::to_string(rows) + " surfels, beyond the limit of " +
                        std::to_string(config_.max_model_surfels));
      }
      SurfelModel model = prefixed("load_file", [&] { return SurfelModel::from_arrays(std::move(arrays)); });
      replace_model(entry, session, std::move(model), reply, updates);
      return;
    }
    case surfeledit_proto_OP_SET_REGIONS: {
      const auto& args = the_argument(request.set_regions, "set_regions");
      SessionEntry& entry = sessions_.attached(session, client);
      const RegionSpec zero = to_core(args.zero, "set_regions.zero");
      const RegionSpec one = to_core(args.one, "set_regions.one");
      prefixed("set_regions", [&] { entry.session->set_regions(zero, one); });
      UpdateEvent event;
      event.session = session;
      event.version = entry.session->version();
      event.cause = "regions";
      updates.push_back(std::move(event));
      reply.session_info = session_info(entry);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_DEFORM: {
      const auto& args = the_argument(request.deform, "deform");
      SessionEntry& entry = sessions_.attached(session, client);
      const DeformParams params = to_core(args, "deform");
      const Clock::time_point t0 = Clock::now();
      StepOutcome result = prefixed("deform", [&] { return entry.session->deform(params); });
      reply.timings.emplace_back("apply", ms_since(t0));
      if (result.detected) reply.timings.emplace_back("detect", result.stats.detect_ms);
      if (!result.inserted.empty()) reply.timings.emplace_back("resample", result.resample_ms);
      entry.steps += 1;
      const std::uint64_t seq = result.seq > 0 ? result.seq : entry.steps;
      const SurfelModel& model = entry.session->model();
      StepInfo step;
      step.seq = seq;
      step.moved = result.moved.size();
      step.center = {result.center.x(), result.center.y(), result.center.z()};
      step.detected = result.detected;
      if (result.depths.size() != result.colliding.size()) {
        throw std::logic_error("step outcome has " + std::to_string(result.depths.size()) + " depths for " +
                               std::to_string(result.colliding.size()) + " colliding ids");
      }
      step.colliding = result.colliding;
      step.depths = result.depths;
      const CollisionStats& cs = result.stats;
      step.stats = CollisionStatsInfo{static_cast<std::uint64_t>(cs.deformable), static_cast<std::uint64_t>(cs.tested),
                                      static_cast<std::uint64_t>(cs.queries),    static_cast<std::uint64_t>(cs.colliding),
                                      cs.detect_ms,                              cs.preprocess_ms};
      step.inserted = result.inserted;
      UpdateEvent event;
      event.session = session;
      event.version = entry.session->version();
      event.cause = "deform";
      event.step = seq;
      event.detected = result.detected;
      event.colliding = std::move(result.colliding);
      // Changed rows: moved or split ones plus the rows of inserted surfels (new ids are changes too).
      event.rows = std::move(result.moved);
      if (!result.inserted.empty()) {
        for (SurfelId id : result.inserted) {
          const Index row = model.row_of(id);
          if (row < 0) throw std::logic_error("inserted id " + std::to_string(id) + " has no row");
          event.rows.push_back(row);
        }
        std::sort(event.rows.begin(), event.rows.end());
        event.rows.erase(std::unique(event.rows.begin(), event.rows.end()), event.rows.end());
      }
      reply.step = std::move(step);
      updates.push_back(std::move(event));
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_CONFIGURE: {
      const auto& args = the_argument(request.configure, "configure");
      SessionEntry& entry = sessions_.attached(session, client);
      const std::vector<NamedSetting> changes = to_core(args, "configure");
      // Errors keep the core's field: the setting's name (PROTOCOL.md).
      entry.session->configure(changes);
      reply.session_info = session_info(entry);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_REMOVE: {
      const auto& args = the_argument(request.remove, "remove");
      SessionEntry& entry = sessions_.attached(session, client);
      IdList ids;
      if (args.ids._length > 0) ids.assign(args.ids._buffer, args.ids._buffer + args.ids._length);
      const std::uint64_t before = entry.session->version();
      prefixed("remove", [&] { entry.session->remove(ids); });
      if (entry.session->version() != before) {
        UpdateEvent event = changes_event(*entry.session, session, before);
        event.cause = "remove";
        updates.push_back(std::move(event));
      }
      reply.session_info = session_info(entry);
      reply.version = entry.session->version();
      return;
    }
    case surfeledit_proto_OP_GET_STATE: {
      const auto& args = the_argument(request.get_state, "get_state");
      SessionEntry& entry = sessions_.attached(session, client);
      reply.state = state_page(*entry.session, args);
      reply.version = entry.session->version();
      return;
    }
  }
  throw Error(ErrorCode::InvalidArgument, "op", "unknown op " + std::to_string(static_cast<long>(request.op)));
}

void Handler::replace_model(SessionEntry& entry, const std::string& session, SurfelModel model, Reply& reply,
                            std::vector<UpdateEvent>& updates) {
  entry.session->load(std::move(model));
  UpdateEvent event;
  event.session = session;
  event.version = entry.session->version();
  event.cause = "load";
  event.full = true;
  event.all_rows = true;
  updates.push_back(std::move(event));
  reply.session_info = session_info(entry);
  reply.version = entry.session->version();
}

SessionInfo Handler::session_info(const SessionEntry& entry) const {
  const EditSession& s = *entry.session;
  SessionInfo info;
  info.name = s.name();
  info.has_regions = s.has_regions();
  info.clients = static_cast<std::uint32_t>(entry.clients.size());
  if (s.has_model()) {
    info.surfels = static_cast<std::uint64_t>(s.model().size());
    info.state_hash = s.state_hash();
    const SessionReport report = s.report();
    info.bytes_per_surfel = report.bytes_per_surfel;
    for (const StructureInfo& st : report.structures) info.structures.emplace_back(st.name, st.bytes);
  }
  for (const NamedSetting& setting : describe(s.settings())) info.settings.push_back(to_reply(setting));
  return info;
}

UpdateEvent Handler::changes_event(const EditSession& s, const std::string& session, std::uint64_t since) const {
  UpdateEvent event;
  event.session = session;
  event.version = s.version();
  if (!s.has_model()) return event;
  const SurfelModel& model = s.model();
  const Changes changes = s.changes_since(since);
  event.full = changes.full;
  event.all_rows = changes.full;
  if (!changes.full) {
    event.rows.reserve(changes.changed.size());
    for (SurfelId id : changes.changed) {
      const Index row = model.row_of(id);
      if (row < 0) throw std::logic_error("changed id " + std::to_string(id) + " has no row");
      event.rows.push_back(row);
    }
    std::sort(event.rows.begin(), event.rows.end());
    event.removed = changes.removed;
    std::sort(event.removed.begin(), event.removed.end());
  }
  return event;
}

std::optional<UpdateEvent> Handler::changes_event(const std::string& session, std::uint64_t since) const {
  const SessionEntry* entry = sessions_.find(session);
  if (!entry) return std::nullopt;
  return changes_event(*entry->session, session, since);
}

ServerInfo Handler::server_info() const {
  ServerInfo info;
  info.version = SURFELEDIT_VERSION;
  info.uptime_s = std::chrono::duration<double>(Clock::now() - started_).count();
  info.sessions = sessions_.names();
  info.max_chunk_surfels = config_.max_chunk_surfels;
  info.max_model_surfels = config_.max_model_surfels;
  return info;
}

StatePage Handler::state_page(const EditSession& session, const surfeledit_proto_GetState& args) const {
  StatePage page;
  page.offset = args.offset;
  if (!session.has_model()) {
    // Nothing loaded yet: the whole (empty) model.
    page.full = true;
    if (args.offset != 0) {
      throw Error(ErrorCode::InvalidArgument, "get_state.offset",
                  "offset " + std::to_string(args.offset) + " beyond the answer's 0 ids");
    }
    return page;
  }
  const SurfelModel& model = session.model();
  Changes changes;
  if (args.changes_only) {
    changes = session.changes_since(args.since_version);
  } else {
    changes.full = true;
  }
  page.full = changes.full;
  // The answer's ids ascending: every id (full) or the changed ones.
  const IdList& answer = changes.full ? model.ids() : changes.changed;
  page.total = answer.size();
  if (args.offset > page.total) {
    throw Error(ErrorCode::InvalidArgument, "get_state.offset",
                "offset " + std::to_string(args.offset) + " beyond the answer's " + std::to_string(page.total) + " ids");
  }
  const std::uint64_t limit =
      (args.max_count == 0 || args.max_count > config_.max_chunk_surfels) ? config_.max_chunk_surfels : args.max_count;
  const std::uint64_t end = std::min<std::uint64_t>(page.total, args.offset + limit);
  const std::size_t n = static_cast<std::size_t>(end - args.offset);
  page.ids.assign(answer.begin() + static_cast<std::ptrdiff_t>(args.offset),
                  answer.begin() + static_cast<std::ptrdiff_t>(end));
  page.positions.resize(3 * n);
  page.normals.resize(3 * n);
  page.radii.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Index row = changes.full ? static_cast<Index>(args.offset + k) : model.row_of(page.ids[k]);
    if (row < 0) throw std::logic_error("changed id " + std::to_string(page.ids[k]) + " has no row");
    for (int c = 0; c < 3; ++c) {
      page.positions[3 * k + c] = model.positions()(row, c);
      page.normals[3 * k + c] = model.normals()(row, c);
    }
    page.radii[k] = model.radii()(row);
  }
  if (args.offset == 0 && !changes.full) page.removed = changes.removed;
  return page;
}

}  // namespace surfeledit::service
