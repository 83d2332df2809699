#include "surfeledit/core/history.hpp"

#include <algorithm>
#include <atomic>

namespace surfeledit {

namespace {

template <typename M>
std::size_t array_bytes(const M& m) {
  return static_cast<std::size_t>(m.size()) * sizeof(typename M::Scalar);
}

}  // namespace

std::size_t SessionImage::bytes() const {
  std::size_t b = sizeof(*this) + colliding.capacity() * sizeof(SurfelId) + (detector ? detector->bytes() : 0);
  if (rows) {
    // A shared row list counts for its share.
    const std::size_t owners = static_cast<std::size_t>(std::max<long>(1, rows->rows.use_count()));
    const std::size_t bent_owners = static_cast<std::size_t>(std::max<long>(1, rows->bent.use_count()));
    b += (rows->rows ? rows->rows->capacity() * sizeof(Index) / owners : 0) +
         (rows->bent ? rows->bent->capacity() * sizeof(Index) / bent_owners : 0) + array_bytes(rows->positions) +
         array_bytes(rows->normals) + array_bytes(rows->tangent_u) + array_bytes(rows->tangent_v) +
         rows->version_runs.capacity() * sizeof(rows->version_runs[0]);
  }
  if (tool_only) b += tool_only->tool.bytes();
  if (whole) {
    b += whole->model.memory_bytes() + whole->row_version.memory_bytes() +
         array_bytes(whole->rest_radius);
    for (const auto& [id, t] : whole->tools) b += id.capacity() + t.bytes();
  }
  return b;
}

const char* SessionImage::kind() const { return rows ? "rows" : tool_only ? "tool" : "whole"; }

void History::push(HistoryEntry entry, std::size_t limit_bytes) {
  std::deque<HistoryEntry> kept;
  for (HistoryEntry& e : entries_) {
    if (e.item.undone && e.item.author == entry.item.author) keep_spare(e);
    else kept.push_back(std::move(e));
  }
  entries_ = std::move(kept);
  entry.item.undone = false;
  share_touched(entry);
  entry.stamp = entry.applied_at = entry.item.version;
  entries_.push_back(std::move(entry));
  HistoryEntry& e = entries_.back();
  e.bytes = e.image->bytes();
  recount();  // the dropped redo tail, and the new entry
  trim(limit_bytes);
}

void History::trim(std::size_t limit_bytes) {
  while (!entries_.empty() && bytes() > limit_bytes) {
    HistoryEntry& front = entries_.front();
    if (front.item.undone) {
      // Its author's later undone entries are redone after it: they cannot be redone without it.
      const std::string author = front.item.author;
      std::deque<HistoryEntry> kept;
      for (HistoryEntry& e : entries_) {
        if (e.item.undone && e.item.author == author) keep_spare(e);
        else kept.push_back(std::move(e));
      }
      entries_ = std::move(kept);
      recount();
      continue;
    }
    bytes_ -= front.bytes;
    count_object(*front.image, -1);
    keep_spare(front);
    entries_.pop_front();
  }
}

HistoryEntry* History::undo_target(const std::string& author) {
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it)
    if (!it->item.undone && it->item.author == author) return &*it;
  return nullptr;
}

HistoryEntry* History::redo_target(const std::string& author) {
  for (HistoryEntry& e : entries_)
    if (e.item.undone && e.item.author == author) return &e;
  return nullptr;
}

HistoryEntry* History::last_applied() {
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it)
    if (!it->item.undone) return &*it;
  return nullptr;
}

HistoryEntry* History::last_undone() {
  HistoryEntry* best = nullptr;
  for (HistoryEntry& e : entries_)
    if (e.item.undone && (!best || e.stamp > best->stamp)) best = &e;
  return best;
}

void History::set_undone(HistoryEntry& entry, bool undone, std::uint64_t stamp) {
  entry.item.undone = undone;
  entry.stamp = stamp;
  if (!undone) entry.applied_at = stamp;
}

void History::keep_spare(HistoryEntry& entry) {
  std::shared_ptr<const SessionImage>& image = entry.image;
  if (image && image->rows && spare_.size() < 2) {
    if (image.use_count() == 1) {
      // No snapshot view shares it (a view that did has let go: its reads happened before).
      std::atomic_thread_fence(std::memory_order_acquire);
      spare_.push_back(std::move(*std::const_pointer_cast<SessionImage>(image)->rows));
    } else {
      // A view still reads it: the spare is a copy, the same as the move would give (version runs with
      // their capacity: the bound counts capacities).
      RowsImage copy = *image->rows;
      copy.version_runs.reserve(image->rows->version_runs.capacity());
      spare_.push_back(std::move(copy));
    }
  }
  retire(image);
}

void History::retire(std::shared_ptr<const SessionImage>& image) {
  if (image && image.use_count() > 1) {
    // Shared with a snapshot view, which reads none of these (their table indices were taken at its point).
    // The image was made non-const (make_shared<SessionImage>), so writing through the cast is defined.
    SessionImage& im = *std::const_pointer_cast<SessionImage>(image);
    if (im.rows) {
      im.rows->rows.reset();
      im.rows->bent.reset();
    }
    im.detector.reset();
    im.detector_object.reset();
    if (im.tool_only) im.tool_only->tool.detector.reset();
    if (im.whole)
      for (auto& [id, t] : im.whole->tools) t.detector.reset();
  }
  image.reset();
}

void History::share_touched(HistoryEntry& entry) {
  if (entry.touched) return;
  // Moved, not copied: the capacity stays (a snapshot writes it).
  entry.touched = std::make_shared<const IdList>(std::move(entry.item.touched));
  entry.item.touched = IdList();
}

History::~History() { clear(); }

History& History::operator=(History&& other) noexcept {
  if (this == &other) return *this;
  clear();
  entries_ = std::move(other.entries_);
  bytes_ = other.bytes_;
  refs_ = std::move(other.refs_);
  spare_ = std::move(other.spare_);
  other.entries_.clear();
  other.bytes_ = 0;
  other.refs_.clear();
  return *this;
}

RowsImage History::take_spare() {
  if (spare_.empty()) return RowsImage();
  RowsImage r = std::move(spare_.back());
  spare_.pop_back();
  return r;
}

void History::clear() {
  for (HistoryEntry& e : entries_) retire(e.image);
  entries_.clear();
  bytes_ = 0;
  refs_.clear();
}

std::vector<HistoryItem> History::items() const {
  std::vector<HistoryItem> out;
  out.reserve(entries_.size());
  for (const HistoryEntry& e : entries_) {
    out.push_back(e.item);
    out.back().touched = *e.touched;
  }
  return out;
}

void History::restore(std::deque<HistoryEntry> entries, std::vector<RowsImage> spare) {
  for (HistoryEntry& e : entries_) retire(e.image);
  entries_ = std::move(entries);
  for (HistoryEntry& e : entries_) share_touched(e);
  spare_ = std::move(spare);
  recount();
}

void History::recount() {
  bytes_ = 0;
  refs_.clear();
  for (const HistoryEntry& e : entries_) {
    bytes_ += e.bytes;
    count_object(*e.image, +1);
  }
}

void History::count_object(const SessionImage& image, int sign) {
  const CollisionDetector* key = image.detector_object.get();
  if (!key) return;
  Ref& r = refs_[key];
  if (sign > 0 && r.refs == 0) r.object = image.detector_object;
  r.refs += sign;
  if (r.refs <= 0) refs_.erase(key);
}

History::Held History::held_detectors() const {
  // An object whose owners are exactly the images that refer to it: no tool and no tool image holds it.
  Held h;
  for (const auto& [key, r] : refs_) {
    if (r.object.use_count() != r.refs) continue;
    ++h.objects;
    h.bytes += key->memory_bytes();
  }
  return h;
}

void History::replace_image(HistoryEntry& entry, SessionImage image) {
  bytes_ -= entry.bytes;
  count_object(*entry.image, -1);
  retire(entry.image);
  entry.image = std::make_shared<SessionImage>(std::move(image));
  entry.bytes = entry.image->bytes();
  bytes_ += entry.bytes;
  count_object(*entry.image, +1);
}

}  // namespace surfeledit
