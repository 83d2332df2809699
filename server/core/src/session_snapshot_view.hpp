// What a SessionSnapshotView holds (session_snapshot_view.hpp): bytes encoded at its point, each
// followed by an entry's touched ids or a history image it shares (with the table indices of that
// image's pointers).
#pragma once

#include <memory>
#include <string>

#include "session_snapshot_images.hpp"
#include "surfeledit/core/history.hpp"
#include "surfeledit/core/session_snapshot_view.hpp"

namespace surfeledit {

struct SessionSnapshotView::Piece {
  std::string bytes;                           // encoded at the point
  std::shared_ptr<const IdList> ids;           // then these ids (an entry's touched; null: none) as a vector
  std::shared_ptr<const SessionImage> image;   // then this image (null: none), encoded by encode()
  snapshot_images::ImageRefs refs;             // its pointers as table indices, taken at the point
};

}  // namespace surfeledit
