// Update samples (proto Update): what changed in a session, cut into chunks of at most
// max_chunk_surfels surfels each.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "surfeledit/core/edit_session.hpp"

namespace surfeledit::service {

// One change to publish, produced by the request handler. The surfels are read from the
// session's model when the chunks are built (right after the request, on the same thread).
struct UpdateEvent {
  std::string session;
  std::uint64_t version = 0;     // session version after the change
  std::string cause;             // "load" | "regions" | "deform" | "close"
  bool full = false;             // a new model (load)
  std::uint64_t step = 0;        // deform: step number
  IndexList rows;                // changed rows of the model (ascending); ignored when all_rows
  bool all_rows = false;         // every row changed (load)
  IdList removed;                // ids removed by the change
};

// One Update sample in C++ form.
struct UpdateChunk {
  std::string session;
  std::uint64_t version = 0;
  std::string cause;
  bool full = false;
  std::uint32_t part = 0;   // 0 .. parts-1
  std::uint32_t parts = 1;
  std::uint64_t step = 0;
  std::vector<std::uint64_t> ids;    // n
  std::vector<double> positions;     // n*3, row-major
  std::vector<double> normals;       // n*3, row-major
  std::vector<double> radii;         // n
  std::vector<std::uint64_t> removed;  // in part 0 only
};

// Number of samples the event needs (at least 1: an event without surfels is one sample).
// `model` is the session's model (nullptr when the event has no surfels, e.g. "close").
std::uint32_t update_parts(const UpdateEvent& event, const SurfelModel* model, std::uint64_t max_chunk_surfels);
// Builds sample `part` (0 .. update_parts()-1) of the event.
UpdateChunk build_update_chunk(const UpdateEvent& event, const SurfelModel* model, std::uint32_t part,
                               std::uint64_t max_chunk_surfels);

}  // namespace surfeledit::service
