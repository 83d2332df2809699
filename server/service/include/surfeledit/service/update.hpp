// Update samples (proto Update): what changed in a session, cut into chunks of at most
// max_chunk_surfels surfels each.
//
// The request handler describes a change as an UpdateEvent (changed rows of the session's model).
// Right after the reply is written, the request thread turns it into a PreparedUpdate: a
// self-contained copy of the changed surfels, so that the session can move on while another
// thread writes the samples (update_publisher.hpp). Samples are slices of a PreparedUpdate.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/service/reply.hpp"

namespace surfeledit::service {

// One change to publish, produced by the request handler. Refers to rows of the session's
// model as it is right after the request.
struct UpdateEvent {
  std::string session;
  std::uint64_t version = 0;     // session version after the change
  std::string cause;             // "load" | "regions" | "deform" | "remove" | "undo" | "redo" | "merge" | "close"
  bool full = false;             // a new model (load)
  std::uint64_t step = 0;        // deform: step number
  IndexList rows;                // changed rows of the model (ascending); ignored when all_rows
  bool all_rows = false;         // every row changed (load)
  IdList removed;                // ids removed by the change
  bool detected = false;         // deform: a collision detector ran; `colliding` is its result
  IdList colliding;              // deform: every colliding id after the step, ascending
  std::string author;            // client id whose op made the change (set by the handler); presence: its subject
  std::string presence;          // cause "presence": "join" | "leave" | "expired" | "regions"
  std::vector<PeerInfo> peers;   // cause "presence": every peer after the change
};

// The one way an event starts: the session, its version after the change and the cause; the
// caller fills what the cause carries (rows, step, collision state).
UpdateEvent make_update_event(const std::string& session, std::uint64_t version, const std::string& cause);
// An event carrying what changed in `s` since version `since` (rows of ids changed or inserted,
// removed ids; the whole model when it was replaced since), at its current version, cause empty.
// Throws std::logic_error when a changed id has no row.
UpdateEvent changes_event(const EditSession& s, const std::string& session, std::uint64_t since);
// Appends the rows of `ids` (every one must be in `model`; std::logic_error naming them `what`
// otherwise) to `rows`.
void append_rows(IndexList& rows, const SurfelModel& model, const IdList& ids, const char* what);

// Everything the samples of one change carry, copied out of the model.
struct PreparedUpdate {
  std::string session;
  std::uint64_t version = 0;
  std::string cause;
  bool full = false;
  std::uint64_t step = 0;
  std::vector<std::uint64_t> ids;      // n, in the event's row order
  std::vector<double> positions;       // n*3, row-major
  std::vector<double> normals;         // n*3, row-major
  std::vector<double> radii;           // n
  std::vector<std::uint64_t> removed;  // sent in part 0
  bool detected = false;               // sent in part 0
  std::vector<std::uint64_t> colliding;  // sent in part 0
  std::vector<double> clip_points;     // n*3, or empty when the model has no clip lines
  std::vector<double> clip_dirs;       // n*3, or empty likewise
  std::string author;                  // sent in every part
  std::string presence;                // sent in every part
  std::vector<PeerInfo> peers;         // sent in part 0

  std::size_t surfels() const { return ids.size(); }
  // Payload bytes held (for the publisher's queue bound).
  std::size_t bytes() const;
};

// Copies the event's surfels out of `model` (the session's model right after the change; may be
// nullptr when the event has no surfels, e.g. "regions" or "close"). Throws std::out_of_range
// for a row outside the model.
PreparedUpdate prepare_update(const UpdateEvent& event, const SurfelModel* model);

// One Update sample: a slice [begin, begin + count) of a PreparedUpdate's surfels. Refers to the
// PreparedUpdate, which must outlive it.
struct UpdateChunk {
  const PreparedUpdate* update = nullptr;
  std::uint32_t part = 0;   // 0 .. parts-1; part 0 also carries removed / detected / colliding
  std::uint32_t parts = 1;
  std::size_t begin = 0;
  std::size_t count = 0;
};

// Number of samples (at least 1: an update without surfels is one sample).
std::uint32_t update_parts(const PreparedUpdate& update, std::uint64_t max_chunk_surfels);
// Sample `part` (0 .. update_parts()-1).
UpdateChunk update_chunk(const PreparedUpdate& update, std::uint32_t part, std::uint64_t max_chunk_surfels);

}  // namespace surfeledit::service
