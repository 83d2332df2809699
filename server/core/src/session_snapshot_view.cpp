// SessionSnapshotView::encode (session_snapshot_view.hpp); EditSession::snapshot_view builds the view
// (session_snapshot.cpp).
#include "session_snapshot_view.hpp"

namespace surfeledit {

SessionSnapshotView::SessionSnapshotView() = default;
SessionSnapshotView::~SessionSnapshotView() = default;
SessionSnapshotView::SessionSnapshotView(SessionSnapshotView&&) noexcept = default;
SessionSnapshotView& SessionSnapshotView::operator=(SessionSnapshotView&&) noexcept = default;

void SessionSnapshotView::encode(SnapshotWriter& out) const {
  // The buffer sized once: each image's bytes() (its arrays' capacities) is about what it encodes to, so a
  // large history is not copied again at every doubling (nor held twice while the buffer grows).
  std::size_t n = out.bytes().size();
  for (const Piece& p : pieces_) {
    n += p.bytes.size();
    if (p.ids) n += 2 * sizeof(std::uint64_t) + p.ids->size() * sizeof(IdList::value_type);
    if (p.image) n += p.image->bytes();
  }
  out.reserve(n);
  for (const Piece& p : pieces_) {
    out.raw(p.bytes.data(), p.bytes.size());
    if (p.ids) out.vec(*p.ids);
    if (p.image) snapshot_images::put_image(out, p.refs, *p.image);
  }
}

std::size_t SessionSnapshotView::copied_bytes() const {
  std::size_t n = 0;
  for (const Piece& p : pieces_) n += p.bytes.size();
  return n;
}

std::size_t SessionSnapshotView::shared_images() const {
  std::size_t n = 0;
  for (const Piece& p : pieces_) n += p.image != nullptr;
  return n;
}

}  // namespace surfeledit
