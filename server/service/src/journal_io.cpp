#include "journal_io.hpp"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "surfeledit/service/journal.hpp"

namespace surfeledit::service::journal {

void fail(const std::string& what, int err) { throw JournalError(what + ": " + std::strerror(err)); }

void put_le(std::uint8_t* p, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::uint64_t get_le(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= std::uint64_t(p[i]) << (8 * i);
  return v;
}

std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
  uLong c = crc;
  while (size > 0) {  // zlib takes uInt lengths
    const std::size_t n = std::min<std::size_t>(size, 1u << 30);
    c = crc32(c, data, static_cast<uInt>(n));
    data += n;
    size -= n;
  }
  return static_cast<std::uint32_t>(c);
}

void write_all(int fd, const std::uint8_t* data, std::size_t size, const std::string& what) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(what, errno);
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

void sync_dir(int dir_fd, const std::string& dir) {
  if (::fsync(dir_fd) != 0) fail("cannot fsync journal directory '" + dir + "'", errno);
}

}  // namespace surfeledit::service::journal
