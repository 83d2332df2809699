// A session's snapshot taken at one point and encoded later, possibly on another thread
// (EditSession::snapshot_view; docs/journal.md "Snapshots: the writer thread").
//
// At its point the view encodes what changes in place or is small -- the detector objects and their
// images' states, the row lists, the scalars, the model, row versions, removal log, rest radii, every
// tool, each history entry's item (but its touched ids) and counters, the spare buffers -- and shares the
// history's images and the entries' touched ids, which are immutable once stored (history.hpp: undo and redo replace an entry's image, buffers are
// reused only from images no view shares). encode() then writes exactly the bytes EditSession::save
// wrote at the view's point (save is snapshot_view().encode()), whatever the session did since (closed
// included). A view is read-only: encode() may run on one thread while the session goes on in another.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit {

class EditSession;

class SessionSnapshotView {
 public:
  SessionSnapshotView();
  ~SessionSnapshotView();
  SessionSnapshotView(SessionSnapshotView&&) noexcept;
  SessionSnapshotView& operator=(SessionSnapshotView&&) noexcept;
  SessionSnapshotView(const SessionSnapshotView&) = delete;
  SessionSnapshotView& operator=(const SessionSnapshotView&) = delete;

  // Appends the session's snapshot as it was at the view's point.
  void encode(SnapshotWriter& out) const;
  // Bytes encoded at the point (the rest is shared history images), and the images shared.
  std::size_t copied_bytes() const;
  std::size_t shared_images() const;

  struct Piece;  // bytes encoded at the point, then an image shared (session_snapshot_view.cpp)

 private:
  friend class EditSession;
  std::vector<Piece> pieces_;
};

}  // namespace surfeledit
