#include "surfeledit/service/update.hpp"

#include <algorithm>
#include <stdexcept>

namespace surfeledit::service {

std::size_t PreparedUpdate::bytes() const {
  return sizeof(*this) + session.size() + cause.size() + ids.size() * sizeof(ids[0]) +
         (positions.size() + normals.size() + radii.size()) * sizeof(double) +
         (removed.size() + colliding.size()) * sizeof(std::uint64_t) +
         (clip_points.size() + clip_dirs.size()) * sizeof(double) + author.size() + presence.size() +
         peers.size() * sizeof(PeerInfo);
}

UpdateEvent make_update_event(const std::string& session, std::uint64_t version, const std::string& cause) {
  UpdateEvent event;
  event.session = session;
  event.version = version;
  event.cause = cause;
  return event;
}

void append_rows(IndexList& rows, const SurfelModel& model, const IdList& ids, const char* what) {
  rows.reserve(rows.size() + ids.size());
  for (SurfelId id : ids) {
    const Index row = model.row_of(id);
    if (row < 0) throw std::logic_error(std::string(what) + " id " + std::to_string(id) + " has no row");
    rows.push_back(row);
  }
}

UpdateEvent changes_event(const EditSession& s, const std::string& session, std::uint64_t since) {
  UpdateEvent event = make_update_event(session, s.version(), "");
  if (!s.has_model()) {  // e.g. the first load undone: a new, empty model
    event.full = since < s.version();
    event.all_rows = event.full;
    return event;
  }
  Changes changes = s.changes_since(since, true);
  event.full = changes.full;
  event.all_rows = changes.full;
  if (!changes.full) {
    event.rows = std::move(changes.rows);  // ascending
    event.removed = changes.removed;
    std::sort(event.removed.begin(), event.removed.end());
  }
  return event;
}

PreparedUpdate prepare_update(const UpdateEvent& event, const SurfelModel* model) {
  PreparedUpdate p;
  p.session = event.session;
  p.version = event.version;
  p.cause = event.cause;
  p.full = event.full;
  p.step = event.step;
  p.removed = event.removed;
  p.detected = event.detected;
  p.colliding = event.colliding;
  p.author = event.author;
  p.presence = event.presence;
  p.peers = event.peers;

  const bool has_surfels = event.all_rows || !event.rows.empty();
  if (!has_surfels || (event.all_rows && !model)) return p;  // a full update without a model: it is empty
  if (!model) throw std::out_of_range("update of session '" + event.session + "' has surfels but no model");
  const std::size_t n = event.all_rows ? static_cast<std::size_t>(model->size()) : event.rows.size();
  const bool clips = model->has_clips();
  // Appended run by run (no zero-filled buffers written twice): a run is consecutive rows, one range copy
  // per array (a step's moved rows are mostly long runs of the model's rows).
  p.ids.reserve(n);
  p.positions.reserve(3 * n);
  p.normals.reserve(3 * n);
  p.radii.reserve(n);
  if (clips) {
    p.clip_points.reserve(3 * n);
    p.clip_dirs.reserve(3 * n);
  }
  const double* pos = model->positions().data();  // row-major: a row's three coordinates are contiguous
  const double* nrm = model->normals().data();
  const double* rad = model->radii().data();
  const Index rows = model->size();
  auto append = [](auto& to, const auto* from, std::size_t begin, std::size_t count) {
    to.insert(to.end(), from + begin, from + begin + count);
  };
  for (std::size_t k = 0; k < n;) {
    std::size_t end = k + 1;
    Index first = static_cast<Index>(k);
    if (event.all_rows) {
      end = n;
    } else {
      first = event.rows[k];
      while (end < n && event.rows[end] == event.rows[end - 1] + 1) ++end;
    }
    const std::size_t count = end - k;
    if (first < 0 || first >= rows || static_cast<std::size_t>(rows - first) < count) {
      throw std::out_of_range("update row out of range");
    }
    const auto row = static_cast<std::size_t>(first);
    for (std::size_t j = 0; j < count; ++j) p.ids.push_back(model->id_of(static_cast<Index>(row + j)));
    append(p.positions, pos, 3 * row, 3 * count);
    append(p.normals, nrm, 3 * row, 3 * count);
    append(p.radii, rad, row, count);
    if (clips) {
      append(p.clip_points, model->clip_points().data(), 3 * row, 3 * count);
      append(p.clip_dirs, model->clip_dirs().data(), 3 * row, 3 * count);
    }
    k = end;
  }
  return p;
}

std::uint32_t update_parts(const PreparedUpdate& update, std::uint64_t max_chunk_surfels) {
  if (max_chunk_surfels == 0) throw std::invalid_argument("max_chunk_surfels must be positive");
  const std::uint64_t n = update.surfels();
  return static_cast<std::uint32_t>(std::max<std::uint64_t>(1, (n + max_chunk_surfels - 1) / max_chunk_surfels));
}

UpdateChunk update_chunk(const PreparedUpdate& update, std::uint32_t part, std::uint64_t max_chunk_surfels) {
  const std::uint32_t parts = update_parts(update, max_chunk_surfels);
  if (part >= parts) throw std::out_of_range("update part out of range");
  const std::uint64_t n = update.surfels();
  const std::uint64_t begin = std::min<std::uint64_t>(n, std::uint64_t(part) * max_chunk_surfels);
  const std::uint64_t end = std::min<std::uint64_t>(n, begin + max_chunk_surfels);
  UpdateChunk c;
  c.update = &update;
  c.part = part;
  c.parts = parts;
  c.begin = static_cast<std::size_t>(begin);
  c.count = static_cast<std::size_t>(end - begin);
  return c;
}

}  // namespace surfeledit::service
