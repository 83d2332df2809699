#include "surfeledit/core/history.hpp"

#include <algorithm>

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
    b += (rows->rows ? rows->rows->capacity() * sizeof(Index) / owners : 0) + array_bytes(rows->positions) +
         array_bytes(rows->normals) + array_bytes(rows->tangent_u) + array_bytes(rows->tangent_v) +
         rows->version_runs.capacity() * sizeof(rows->version_runs[0]);
  }
  if (whole) {
    b += whole->model.memory_bytes() + whole->row_version.capacity() * sizeof(std::uint64_t) +
         array_bytes(whole->rest_radius);
    for (const auto& [id, t] : whole->tools) b += id.capacity() + t.bytes();
  }
  return b;
}

void History::push(HistoryEntry entry, std::size_t limit_bytes) {
  for (std::size_t k = applied_; k < entries_.size(); ++k) keep_spare(entries_[k]);
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
    keep_spare(entries_.front());
    entries_.pop_front();
    if (applied_ > 0) --applied_;
  }
}

HistoryEntry* History::undo_target() { return applied_ > 0 ? &entries_[applied_ - 1] : nullptr; }

HistoryEntry* History::redo_target() { return applied_ < entries_.size() ? &entries_[applied_] : nullptr; }

void History::keep_spare(HistoryEntry& entry) {
  if (entry.image.rows && spare_.size() < 2) spare_.push_back(std::move(*entry.image.rows));
}

RowsImage History::take_spare() {
  if (spare_.empty()) return RowsImage();
  RowsImage r = std::move(spare_.back());
  spare_.pop_back();
  return r;
}

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
