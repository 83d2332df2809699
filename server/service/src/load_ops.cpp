// Handler functions of the load ops: LOAD_BEGIN, LOAD_CHUNK, LOAD_COMMIT (inline upload, see
// upload.hpp) and LOAD_FILE.
#include "handler_ops.hpp"
#include "surfeledit/core/model_io.hpp"

namespace surfeledit::service {

namespace {

// The client's upload into the session; Conflict naming `field` when none is in progress.
Upload& upload_in_progress(OpContext& c, const char* field) {
  Upload* upload = c.state.uploads.find(c.command.client_id, c.command.session);
  if (!upload) throw Error(ErrorCode::Conflict, field, "no upload in progress: send OP_LOAD_BEGIN first");
  return *upload;
}

// Replaces the session's model and announces a full update.
void replace_model(OpContext& c, SurfelModel model) {
  EditSession& s = *c.entry->session;
  s.load(std::move(model), c.command.client_id);
  UpdateEvent event = make_update_event(c.command.session, s.version(), "load");
  event.full = true;
  event.all_rows = true;
  c.updates.push_back(std::move(event));
}

}  // namespace

void serve_load_begin(OpContext& c) {
  const auto& args = args_of<LoadBeginArgs>(c);
  c.state.uploads.begin(c.command.client_id, c.command.session, args.total, args.has_radii);
}

void serve_load_chunk(OpContext& c) {
  c.state.uploads.add_chunk(c.command.client_id, c.command.session, args_of<ChunkData>(c));
}

void serve_load_commit(OpContext& c) {
  Upload& upload = upload_in_progress(c, "op");
  if (!upload.complete()) {
    throw Error(ErrorCode::Conflict, "load_begin.total",
                "upload incomplete: received " + std::to_string(upload.received()) + " of " +
                    std::to_string(upload.total()) + " surfels");
  }
  SurfelArrays arrays = upload.arrays();
  prefixed("load_chunk", [&] { validate_arrays(arrays); });
  c.state.uploads.erase(c.command.client_id, c.command.session);
  SurfelModel model = prefixed("load_chunk", [&] { return SurfelModel::from_arrays(std::move(arrays)); });
  replace_model(c, std::move(model));
}

void serve_load_file(OpContext& c) {
  const std::string requested = args_of<LoadFileArgs>(c).path;
  const std::string path = c.state.data_root.resolve(requested);  // below the root, regular, within the size limit
  if (c.state.loads.busy(c.command.session)) {
    throw Error(ErrorCode::Conflict, "load_file",
                "a file load into session '" + c.command.session + "' is in progress; retry when it finished");
  }
  if (c.state.loads.running() >= FileLoads::kMaxRunning) {
    throw Error(ErrorCode::Conflict, "load_file",
                "the server is reading " + std::to_string(FileLoads::kMaxRunning) +
                    " files already; retry when one finished");
  }
  FileLoad load;
  load.client_id = c.command.client_id;
  load.request_id = c.command.request_id;
  load.session = c.command.session;
  load.started = std::chrono::steady_clock::now();
  LoadParams params;
  params.max_points = c.state.config.max_model_surfels;
  // Off the request thread; errors quote the path as the client gave it, never where it resolved to.
  c.state.loads.start(std::move(load), [path, requested, params] {
    try {
      return load_surfels(path, params);
    } catch (const Error& e) {
      std::string message = message_of(e);
      for (std::size_t at = message.find(path); at != std::string::npos; at = message.find(path, at + requested.size()))
        message.replace(at, path.size(), requested);
      throw Error(e.code(), e.field(), message);
    }
  });
  c.deferred = true;
}

void finish_load_file(HandlerState& state, FileLoad& load, Reply& reply, std::vector<UpdateEvent>& updates) {
  Command command;
  command.client_id = load.client_id;
  command.request_id = load.request_id;
  command.session = load.session;
  command.op = Op::LoadFile;
  // The client may have left (or the session closed) while the file was read: then nothing is loaded.
  OpContext c{state, command, &state.sessions.attached(load.session, load.client_id), reply, updates};
  if (load.error) prefixed("load_file", [&] { std::rethrow_exception(load.error); });
  SurfelArrays arrays = std::move(*load.arrays);
  load.arrays.reset();
  const auto rows = static_cast<std::uint64_t>(arrays.positions.rows());
  const std::uint64_t limit = state.config.max_model_surfels;
  if (rows > limit) {
    throw Error(ErrorCode::TooLarge, "load_file.path",
                "the file holds " + std::to_string(rows) + " surfels, beyond the limit of " + std::to_string(limit));
  }
  SurfelModel model = prefixed("load_file", [&] { return SurfelModel::from_arrays(std::move(arrays)); });
  const std::uint64_t version_before = c.entry->session->version();
  replace_model(c, std::move(model));
  note_activity(*c.entry, load.client_id, Op::LoadFile, version_before, std::chrono::steady_clock::now());
  fill_reply_tail(reply, *c.entry, ReplyTail::VersionAndSessionInfo, load.client_id);
}

}  // namespace surfeledit::service
