// Handler function of GET_STATE: one page of the model, or of what changed since a version.
#include <algorithm>

#include "handler_ops.hpp"

namespace surfeledit::service {

namespace {

StatePage state_page(const EditSession& session, const GetStateArgs& args, std::uint64_t max_chunk_surfels) {
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
  page.total = changes.full ? static_cast<std::uint64_t>(model.size()) : changes.changed.size();
  if (args.offset > page.total) {
    throw Error(ErrorCode::InvalidArgument, "get_state.offset",
                "offset " + std::to_string(args.offset) + " beyond the answer's " + std::to_string(page.total) + " ids");
  }
  const std::uint64_t limit =
      (args.max_count == 0 || args.max_count > max_chunk_surfels) ? max_chunk_surfels : args.max_count;
  const std::uint64_t end = std::min<std::uint64_t>(page.total, args.offset + limit);
  const std::size_t n = static_cast<std::size_t>(end - args.offset);
  page.ids.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    page.ids[k] = changes.full ? model.id_of(static_cast<Index>(args.offset + k)) : changes.changed[args.offset + k];
  page.positions.resize(3 * n);
  page.normals.resize(3 * n);
  page.radii.resize(n);
  const bool clips = model.has_clips();
  if (clips) {
    page.clip_points.resize(3 * n);
    page.clip_dirs.resize(3 * n);
  }
  for (std::size_t k = 0; k < n; ++k) {
    const Index row = changes.full ? static_cast<Index>(args.offset + k) : model.row_of(page.ids[k]);
    if (row < 0) throw std::logic_error("changed id " + std::to_string(page.ids[k]) + " has no row");
    for (int c = 0; c < 3; ++c) {
      page.positions[3 * k + c] = model.positions()(row, c);
      page.normals[3 * k + c] = model.normals()(row, c);
      if (clips) {
        page.clip_points[3 * k + c] = model.clip_points()(row, c);
        page.clip_dirs[3 * k + c] = model.clip_dirs()(row, c);
      }
    }
    page.radii[k] = model.radii()(row);
  }
  if (args.offset == 0 && !changes.full) page.removed = changes.removed;
  return page;
}

}  // namespace

void serve_get_state(OpContext& c) {
  c.reply.state = state_page(*c.entry->session, args_of<GetStateArgs>(c), c.state.config.max_chunk_surfels);
}

}  // namespace surfeledit::service
