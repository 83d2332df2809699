#include "surfeledit/service/update.hpp"

#include <algorithm>
#include <stdexcept>

namespace surfeledit::service {

namespace {

std::uint64_t surfel_count(const UpdateEvent& event, const SurfelModel* model) {
  if (!model) return 0;
  return event.all_rows ? static_cast<std::uint64_t>(model->size()) : event.rows.size();
}

}  // namespace

std::uint32_t update_parts(const UpdateEvent& event, const SurfelModel* model, std::uint64_t max_chunk_surfels) {
  if (max_chunk_surfels == 0) throw std::invalid_argument("max_chunk_surfels must be positive");
  const std::uint64_t n = surfel_count(event, model);
  return static_cast<std::uint32_t>(std::max<std::uint64_t>(1, (n + max_chunk_surfels - 1) / max_chunk_surfels));
}

UpdateChunk build_update_chunk(const UpdateEvent& event, const SurfelModel* model, std::uint32_t part,
                               std::uint64_t max_chunk_surfels) {
  const std::uint32_t parts = update_parts(event, model, max_chunk_surfels);
  if (part >= parts) throw std::out_of_range("update part out of range");
  UpdateChunk chunk;
  chunk.session = event.session;
  chunk.version = event.version;
  chunk.cause = event.cause;
  chunk.full = event.full;
  chunk.part = part;
  chunk.parts = parts;
  chunk.step = event.step;
  if (part == 0) chunk.removed = event.removed;

  const std::uint64_t n = surfel_count(event, model);
  const std::uint64_t begin = std::min<std::uint64_t>(n, std::uint64_t(part) * max_chunk_surfels);
  const std::uint64_t end = std::min<std::uint64_t>(n, begin + max_chunk_surfels);
  const std::size_t count = static_cast<std::size_t>(end - begin);
  chunk.ids.resize(count);
  chunk.positions.resize(count * 3);
  chunk.normals.resize(count * 3);
  chunk.radii.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const Index row = event.all_rows ? static_cast<Index>(begin + k) : event.rows[begin + k];
    if (row < 0 || row >= model->size()) throw std::out_of_range("update row out of range");
    chunk.ids[k] = model->ids()[row];
    for (int c = 0; c < 3; ++c) {
      chunk.positions[3 * k + c] = model->positions()(row, c);
      chunk.normals[3 * k + c] = model->normals()(row, c);
    }
    chunk.radii[k] = model->radii()(row);
  }
  return chunk;
}

}  // namespace surfeledit::service
