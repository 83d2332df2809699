// RowVersions (row_versions.hpp): 32-bit offsets from a floor that rises when a version outgrows them.
#include "surfeledit/core/row_versions.hpp"

#include "surfeledit/core/util.hpp"

namespace surfeledit {

void RowVersions::assign(std::size_t rows, std::uint64_t version) {
  floor_ = version;
  off_.assign(rows, 0u);
}

void RowVersions::resize(std::size_t rows, std::uint64_t version) {
  const std::size_t old = off_.size();
  off_.resize(rows, 0u);
  for (std::size_t r = old; r < rows; ++r) set(r, version);
}

void RowVersions::compact(const std::vector<bool>& keep) { surfeledit::compact(off_, keep); }

RowVersions RowVersions::from_parts(std::uint64_t floor, std::vector<std::uint32_t> offsets) {
  RowVersions v;
  v.floor_ = floor;
  v.off_ = std::move(offsets);
  return v;
}

void RowVersions::raise_floor(std::uint64_t version) {
  const std::uint64_t floor = version - kSpan / 2;
  for (std::uint32_t& o : off_) {
    const std::uint64_t v = floor_ + o;
    o = v > floor ? static_cast<std::uint32_t>(v - floor) : 0u;
  }
  floor_ = floor;
}

}  // namespace surfeledit
