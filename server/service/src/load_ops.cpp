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
  const std::string& path = args_of<LoadFileArgs>(c).path;
  SurfelArrays arrays = prefixed("load_file", [&] { return load_surfels(path); });
  const auto rows = static_cast<std::uint64_t>(arrays.positions.rows());
  const std::uint64_t limit = c.state.config.max_model_surfels;
  if (rows > limit) {
    throw Error(ErrorCode::TooLarge, "load_file.path",
                "'" + path + "' holds " + std::to_string(rows) + " surfels, beyond the limit of " +
                    std::to_string(limit));
  }
  SurfelModel model = prefixed("load_file", [&] { return SurfelModel::from_arrays(std::move(arrays)); });
  replace_model(c, std::move(model));
}

}  // namespace surfeledit::service
