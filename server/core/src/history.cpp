#include "surfeledit/core/history.hpp"

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
    b += rows->rows.capacity() * sizeof(Index) + array_bytes(rows->positions) + array_bytes(rows->normals) +
         array_bytes(rows->tangent_u) + array_bytes(rows->tangent_v) +
         rows->row_version.capacity() * sizeof(std::uint64_t);
  }
  if (whole) {
    b += whole->model.memory_bytes() + whole->row_version.capacity() * sizeof(std::uint64_t) +
         array_bytes(whole->rest_radius) + (whole->fields ? whole->fields->memory_bytes() : 0) +
         (whole->detector ? whole->detector->memory_bytes() : 0);
  }
  return b;
}

void History::push(HistoryEntry entry, std::size_t limit_bytes) {
  entries_.resize(applied_);
  entries_.push_back(std::move(entry));
  applied_ = entries_.size();
  recount();  // the dropped redo tail
  HistoryEntry& e = entries_.back();
  e.bytes = e.image.bytes();
  bytes_ += e.bytes;
  trim(limit_bytes);
}

void History::trim(std::size_t limit_bytes) {
  while (!entries_.empty() && bytes_ > limit_bytes) {
    if (applied_ == 0) {  // only a redo tail is left: its entries need the ones before them
      clear();
      return;
    }
    bytes_ -= entries_.front().bytes;
    entries_.pop_front();
    if (applied_ > 0) --applied_;
  }
}

HistoryEntry* History::undo_target() { return applied_ > 0 ? &entries_[applied_ - 1] : nullptr; }

HistoryEntry* History::redo_target() { return applied_ < entries_.size() ? &entries_[applied_] : nullptr; }

void History::clear() {
  entries_.clear();
  applied_ = 0;
  bytes_ = 0;
}

std::vector<HistoryItem> History::items() const {
  std::vector<HistoryItem> out;
  out.reserve(entries_.size());
  for (std::size_t k = 0; k < entries_.size(); ++k) {
    out.push_back(entries_[k].item);
    out.back().undone = k >= applied_;
  }
  return out;
}

void History::recount() {
  bytes_ = 0;
  for (const HistoryEntry& e : entries_) bytes_ += e.bytes;
}

void History::replace_image(HistoryEntry& entry, SessionImage image) {
  bytes_ -= entry.bytes;
  entry.image = std::move(image);
  entry.bytes = entry.image.bytes();
  bytes_ += entry.bytes;
}

}  // namespace surfeledit
