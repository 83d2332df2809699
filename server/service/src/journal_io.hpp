// Small file helpers the journal's log and snapshot files share: errors naming errno, little-endian
// integers, CRC-32, whole writes and directory fsyncs. Private to the service.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace surfeledit::service::journal {

// Throws JournalError "<what>: <strerror(err)>".
[[noreturn]] void fail(const std::string& what, int err);

// `bytes` (1..8) little-endian bytes of `v` at `p`, and back.
void put_le(std::uint8_t* p, std::uint64_t v, int bytes);
std::uint64_t get_le(const std::uint8_t* p, int bytes);

// CRC-32 (zlib) of `size` bytes continuing `crc` (0 to start); any size.
std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

// Writes all `size` bytes to `fd`, again after a short write or EINTR; throws JournalError "<what>: <error>".
void write_all(int fd, const std::uint8_t* data, std::size_t size, const std::string& what);

// Forces the entries of directory `dir` (open as `dir_fd`) to disk. Throws JournalError.
void sync_dir(int dir_fd, const std::string& dir);

}  // namespace surfeledit::service::journal
