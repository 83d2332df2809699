#include "journal_snapshot.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <vector>

namespace surfeledit::service::journal {

namespace {

constexpr std::array<char, 8> kMagic = {'S', 'E', 'S', 'N', 'A', 'P', 'S', 'H'};
constexpr std::uint32_t kFileFormat = 1;
constexpr std::size_t kHeaderBytes = kSnapshotHeaderBytes;

}  // namespace

std::string snapshot_path(const std::string& dir, std::uint64_t seq) {
  return dir + "/snapshot-" + std::to_string(seq) + ".bin";
}

SnapshotRecord write_snapshot_file(const std::string& dir, int dir_fd, std::uint64_t seq,
                                   const std::vector<std::string>& parts, SnapshotFileTimes* times) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const std::string path = snapshot_path(dir, seq);
  const std::string tmp = path + ".tmp";
  std::uint64_t payload = 0;
  for (const std::string& part : parts) payload += part.size();
  std::array<std::uint8_t, kHeaderBytes> header{};
  std::memcpy(header.data(), kMagic.data(), kMagic.size());
  put_le(header.data() + 8, kFileFormat, 4);
  put_le(header.data() + 12, kRecordFormat, 4);
  put_le(header.data() + 16, seq, 8);
  put_le(header.data() + 24, payload, 8);
  SnapshotRecord record;
  record.seq = seq;
  record.file_bytes = kHeaderBytes + payload;
  record.file_crc = crc32_of(header.data(), header.size());
  for (const std::string& part : parts) {
    record.file_crc = crc32_of(reinterpret_cast<const std::uint8_t*>(part.data()), part.size(), record.file_crc);
  }
  try {
    UniqueFd fd(::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600));
    if (fd.get() < 0) fail("cannot create snapshot '" + tmp + "'", errno);
    const std::string what = "cannot write snapshot '" + tmp + "'";
    write_all(fd.get(), header.data(), header.size(), what);
    for (const std::string& part : parts) {
      write_all(fd.get(), reinterpret_cast<const std::uint8_t*>(part.data()), part.size(), what);
    }
    const auto t1 = Clock::now();
    if (::fdatasync(fd.get()) != 0) fail("cannot fdatasync snapshot '" + tmp + "'", errno);
    if (::rename(tmp.c_str(), path.c_str()) != 0) fail("cannot rename snapshot '" + tmp + "'", errno);
    sync_dir(dir_fd, dir);
    if (times) {
      times->write_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
      times->sync_ms = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
    }
  } catch (...) {
    ::unlink(tmp.c_str());
    ::unlink(path.c_str());
    throw;
  }
  return record;
}

std::string read_snapshot_file(const std::string& dir, const SnapshotRecord& record) {
  const std::string path = snapshot_path(dir, record.seq);
  UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) fail("cannot open snapshot '" + path + "'", errno);
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) fail("cannot stat snapshot '" + path + "'", errno);
  if (static_cast<std::uint64_t>(st.st_size) != record.file_bytes) {
    throw JournalError("snapshot '" + path + "' has " + std::to_string(st.st_size) + " bytes, its record says " +
                       std::to_string(record.file_bytes));
  }
  if (record.file_bytes < kHeaderBytes) throw JournalError("snapshot '" + path + "' has no complete header");
  std::string bytes(static_cast<std::size_t>(record.file_bytes), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::pread(fd.get(), bytes.data() + done, bytes.size() - done, static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail("cannot read snapshot '" + path + "'", errno);
    if (n == 0) throw JournalError("snapshot '" + path + "' shrank while it was read");
    done += static_cast<std::size_t>(n);
  }
  const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
  if (crc32_of(p, bytes.size()) != record.file_crc) {
    throw JournalError("snapshot '" + path + "' does not match its record's checksum (corrupt)");
  }
  if (std::memcmp(p, kMagic.data(), kMagic.size()) != 0 || get_le(p + 8, 4) != kFileFormat ||
      get_le(p + 12, 4) < kOldestRecordFormat || get_le(p + 12, 4) > kRecordFormat || get_le(p + 16, 8) != record.seq ||
      get_le(p + 24, 8) != record.file_bytes - kHeaderBytes) {
    throw JournalError("snapshot '" + path + "' has another header (format, record format or number)");
  }
  return bytes;
}

void remove_snapshots_before(const std::string& dir, int dir_fd, std::uint64_t seq) {
  std::error_code ec;
  std::vector<std::string> doomed;
  for (const auto& item : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = item.path().filename().string();
    if (name.rfind("snapshot-", 0) != 0) continue;
    const std::size_t dot = name.find('.');
    const std::string digits = name.substr(9, dot == std::string::npos ? std::string::npos : dot - 9);
    if (digits.empty() || digits.size() > 18 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const bool tmp = name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0;
    if (std::stoull(digits) < seq || tmp) doomed.push_back(item.path().string());
  }
  if (ec) fail("cannot list journal directory '" + dir + "'", ec.value());
  for (const std::string& path : doomed) {
    if (::unlink(path.c_str()) != 0 && errno != ENOENT) fail("cannot remove snapshot '" + path + "'", errno);
  }
  if (!doomed.empty()) sync_dir(dir_fd, dir);
}

}  // namespace surfeledit::service::journal
