#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit {

void SnapshotReader::fail(const char* what, const std::string& why) const {
  throw Error(ErrorCode::InvalidArgument, "snapshot",
              std::string("corrupt snapshot: ") + what + " at byte " + std::to_string(at_) + ": " + why);
}

void SnapshotReader::raw(void* out, std::size_t n, const char* what) {
  if (n > remaining()) fail(what, "needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) + " left");
  if (n) std::memcpy(out, p_ + at_, n);
  at_ += n;
}

bool SnapshotReader::boolean(const char* what) {
  const std::uint8_t v = u8(what);
  if (v > 1) fail(what, "not a bool (" + std::to_string(v) + ")");
  return v == 1;
}

std::size_t SnapshotReader::count(const char* what, std::size_t item_bytes) {
  const std::uint64_t n = u64(what);
  if (item_bytes > 0 && n > remaining() / item_bytes) fail(what, "count " + std::to_string(n) + " larger than the bytes left");
  if (item_bytes == 0 && n > remaining()) fail(what, "count " + std::to_string(n) + " larger than the bytes left");
  return static_cast<std::size_t>(n);
}

std::string SnapshotReader::str(const char* what) {
  const std::size_t n = count(what, 1);
  std::string s(n, '\0');
  raw(s.data(), n, what);
  return s;
}

void SnapshotReader::expect_end() const {
  if (remaining() != 0) fail("end", std::to_string(remaining()) + " bytes left over");
}

}  // namespace surfeledit
