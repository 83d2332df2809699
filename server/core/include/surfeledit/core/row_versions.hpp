// Per row of a session's model: the session version of the row's last change (EditSession::changes_since),
// in 4 bytes a row: a 32-bit offset from a floor. Versions are 64-bit; a row's reads as floor + offset.
//
// Overflow (a session past 2^32 versions since its floor): setting a version more than kSpan above the floor
// first raises the floor to that version - kSpan / 2; every row whose version is below the new floor then
// reads as the floor ("changed at or before floor()"), the others keep theirs exactly. A version below the
// floor (an old one a history image puts back) reads as the floor too. So a question "what changed since s"
// is exact for s >= floor(); the session answers s < floor() with a full update (changes_since).
#pragma once

#include <cstdint>
#include <vector>

namespace surfeledit {

class RowVersions {
 public:
  static constexpr std::uint64_t kSpan = 0xffffffffull;  // largest offset above the floor

  std::size_t size() const { return off_.size(); }
  std::uint64_t floor() const { return floor_; }
  std::uint64_t operator[](std::size_t row) const { return floor_ + off_[row]; }
  void set(std::size_t row, std::uint64_t version) {
    if (version > floor_ + kSpan) raise_floor(version);
    off_[row] = version > floor_ ? static_cast<std::uint32_t>(version - floor_) : 0u;
  }
  void assign(std::size_t rows, std::uint64_t version);  // every row at `version` (the floor: `version`)
  void resize(std::size_t rows, std::uint64_t version);  // new rows at `version`
  void push_back(std::uint64_t version) {
    off_.push_back(0);
    set(off_.size() - 1, version);
  }
  void compact(const std::vector<bool>& keep);  // keeps the rows with keep[r], in order
  std::size_t memory_bytes() const { return off_.capacity() * sizeof(std::uint32_t); }

  // For snapshots: the floor and the offsets as they are; from_parts() checks nothing beyond its types.
  const std::vector<std::uint32_t>& offsets() const { return off_; }
  static RowVersions from_parts(std::uint64_t floor, std::vector<std::uint32_t> offsets);

 private:
  void raise_floor(std::uint64_t version);
  std::uint64_t floor_ = 0;
  std::vector<std::uint32_t> off_;  // per row: version - floor_ (0: at or before the floor)
};

}  // namespace surfeledit
