// The journal's log file: framing, checksums, cutting a torn tail, appending and fdatasync.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include "journal_io.hpp"
#include "surfeledit/service/journal.hpp"
#include "surfeledit/service/log.hpp"

namespace surfeledit::service {

namespace {

constexpr std::array<char, 8> kJournalMagic = {'S', 'E', 'J', 'O', 'U', 'R', 'N', 'L'};
constexpr std::uint32_t kJournalFormat = 1;       // framing version in the header
constexpr std::size_t kHeaderBytes = 16;   // magic, format, record format, reserved
constexpr std::size_t kFrameBytes = 9;     // length, crc, kind

using journal::fail;

void put_u32(std::uint8_t* p, std::uint32_t v) { journal::put_le(p, v, 4); }
std::uint32_t get_u32(const std::uint8_t* p) { return static_cast<std::uint32_t>(journal::get_le(p, 4)); }

// CRC-32 of the kind byte and the payload.
std::uint32_t checksum(std::uint8_t kind, const std::uint8_t* payload, std::size_t size) {
  return journal::crc32_of(payload, size, journal::crc32_of(&kind, 1));
}

// Reads exactly `size` bytes at `offset`; false at end of file first.
bool read_at(int fd, std::uint64_t offset, std::uint8_t* out, std::size_t size, const std::string& path) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd, out + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot read journal '" + path + "'", errno);
    }
    if (n == 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}


// The header of a new segment.
std::array<std::uint8_t, kHeaderBytes> new_header() {
  std::array<std::uint8_t, kHeaderBytes> header{};
  std::memcpy(header.data(), kJournalMagic.data(), kJournalMagic.size());
  put_u32(header.data() + 8, kJournalFormat);
  put_u32(header.data() + 12, kRecordFormat);
  return header;
}

bool known_kind(std::uint8_t kind) {
  return kind == static_cast<std::uint8_t>(RecordKind::Request) ||
         kind == static_cast<std::uint8_t>(RecordKind::Refusal) ||
         kind == static_cast<std::uint8_t>(RecordKind::Expiry) || kind == static_cast<std::uint8_t>(RecordKind::Snapshot);
}

}  // namespace

UniqueFd::~UniqueFd() {
  if (fd_ >= 0) ::close(fd_);
}

UniqueFd& UniqueFd::operator=(UniqueFd&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

std::string JournalLog::segment_path(const std::string& dir, std::uint64_t segment) {
  return segment == 0 ? dir + "/journal.log" : dir + "/journal-" + std::to_string(segment) + ".log";
}

JournalLog::JournalLog(const std::string& dir,
                       const std::function<void(RecordKind, const std::vector<std::uint8_t>&)>& on_record)
    : JournalLog(dir) {
  read(0, on_record);
}

JournalLog::JournalLog(const std::string& dir) : dir_(dir) {
  if (dir.empty()) throw JournalError("journal directory is empty");
  if (::mkdir(dir.c_str(), 0700) == 0) {
    // A new directory: its entry in the parent must reach the disk too.
    const std::string parent = dir.find('/') == std::string::npos ? "." : dir.substr(0, dir.find_last_of('/') + 1);
    UniqueFd parent_fd(::open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
    if (parent_fd.get() < 0 || ::fsync(parent_fd.get()) != 0) fail("cannot fsync the parent of '" + dir + "'", errno);
  } else if (errno != EEXIST) {
    fail("cannot create journal directory '" + dir + "'", errno);
  }
  dir_fd_ = UniqueFd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir_fd_.get() < 0) fail("cannot open journal directory '" + dir + "'", errno);
  if (::flock(dir_fd_.get(), LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) throw JournalError("journal directory '" + dir + "' is in use by another server");
    fail("cannot lock journal directory '" + dir + "'", errno);
  }
  // The segments, by number: journal.log is 0, journal-<k>.log is k.
  std::set<std::uint64_t> segments;
  std::error_code ec;
  for (const auto& item : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = item.path().filename().string();
    if (name == "journal.log") {
      segments.insert(0);
    } else if (name.rfind("journal-", 0) == 0 && name.size() > 12 && name.compare(name.size() - 4, 4, ".log") == 0) {
      const std::string digits = name.substr(8, name.size() - 12);
      if (digits.find_first_not_of("0123456789") == std::string::npos && digits.size() < 19 && digits[0] != '0') {
        segments.insert(std::stoull(digits));
      }
    }
  }
  if (ec) fail("cannot list journal directory '" + dir + "'", ec.value());
  if (segments.empty()) segments.insert(0);
  if (*segments.rbegin() - *segments.begin() + 1 != segments.size()) {
    throw JournalError("journal '" + dir + "': segments " + std::to_string(*segments.begin()) + " to " +
                       std::to_string(*segments.rbegin()) + " have gaps (a segment file was removed)");
  }
  first_ = *segments.begin();
  // A newest segment k > 0 holding at most its header (created ahead for the next snapshot, or cut while
  // it was started) goes first: the one before it is then the last, whose torn tail may be cut.
  if (segments.size() > 1) {
    const std::string newest = segment_path(dir_, *segments.rbegin());
    struct stat st {};
    if (::stat(newest.c_str(), &st) == 0 && static_cast<std::uint64_t>(st.st_size) <= kHeaderBytes) {
      if (::unlink(newest.c_str()) != 0) fail("cannot remove the empty journal segment '" + newest + "'", errno);
      sync_dir();
      segments.erase(std::prev(segments.end()));
    }
  }
  for (std::uint64_t k : segments) scan(k, k == *segments.rbegin());
  // A newest segment k > 0 without any record (its first one torn): appends go to the one before.
  if (segment_ > first_ && (index_.empty() || index_.back().segment != segment_)) {
    fd_ = UniqueFd();
    if (::unlink(path_.c_str()) != 0) fail("cannot remove the empty journal segment '" + path_ + "'", errno);
    sync_dir();
    --segment_;
    path_ = segment_path(dir_, segment_);
    size_ = older_.at(segment_);
    older_.erase(segment_);
    fd_ = UniqueFd(::open(path_.c_str(), O_RDWR | O_CLOEXEC));
    if (fd_.get() < 0) fail("cannot open journal '" + path_ + "'", errno);
  }
}

void JournalLog::scan(std::uint64_t segment, bool last) {
  if (fd_.get() >= 0) older_[segment_] = size_;
  segment_ = segment;
  path_ = segment_path(dir_, segment);
  bool created = false;
  fd_ = UniqueFd(::open(path_.c_str(), O_RDWR | O_CLOEXEC));
  if (fd_.get() < 0 && errno == ENOENT && segment == 0) {
    fd_ = UniqueFd(::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600));
    created = true;
  }
  if (fd_.get() < 0) fail("cannot open journal '" + path_ + "'", errno);
  struct stat st {};
  if (::fstat(fd_.get(), &st) != 0) fail("cannot stat journal '" + path_ + "'", errno);
  const auto file_size = static_cast<std::uint64_t>(st.st_size);

  if (file_size < kHeaderBytes) {
    if (!last) throw JournalError("journal segment '" + path_ + "' has no complete header but later segments exist");
    // New, or cut short before its header was complete (nothing can follow then): write the header.
    if (file_size > 0) logger()->warn("journal '{}': {} byte(s) without a complete header; starting it anew", path_, file_size);
    if (::ftruncate(fd_.get(), 0) != 0) fail("cannot truncate journal '" + path_ + "'", errno);
    const std::array<std::uint8_t, kHeaderBytes> header = new_header();
    if (::lseek(fd_.get(), 0, SEEK_SET) < 0) fail("cannot seek in journal '" + path_ + "'", errno);
    journal::write_all(fd_.get(), header.data(), header.size(), "cannot append to journal '" + path_ + "'");
    if (::fsync(fd_.get()) != 0) fail("cannot fsync journal '" + path_ + "'", errno);
    if (created && ::fsync(dir_fd_.get()) != 0) fail("cannot fsync journal directory '" + dir_ + "'", errno);
    size_ = kHeaderBytes;
    cut_bytes_ += file_size;
    return;
  }
  std::array<std::uint8_t, kHeaderBytes> header{};
  read_at(fd_.get(), 0, header.data(), header.size(), path_);
  if (std::memcmp(header.data(), kJournalMagic.data(), kJournalMagic.size()) != 0) {
    throw JournalError("'" + path_ + "' is not a surfeledit journal (bad magic)");
  }
  if (get_u32(header.data() + 8) != kJournalFormat) {
    throw JournalError("journal '" + path_ + "' has format " + std::to_string(get_u32(header.data() + 8)) +
                       "; this server reads format " + std::to_string(kJournalFormat));
  }
  const std::uint32_t records = get_u32(header.data() + 12);
  if (records < kOldestRecordFormat || records > kRecordFormat) {
    throw JournalError("journal '" + path_ + "' holds records of format " + std::to_string(records) +
                       (records == 0 ? " (written before record formats were recorded: its requests may lack fields "
                                       "added since, e.g. the blend / fill_holes projection)"
                                     : "") +
                       "; this server reads record formats " + std::to_string(kOldestRecordFormat) + " to " +
                       std::to_string(kRecordFormat) +
                       ": recover it with the server that wrote it, or move it away");
  }

  // Intact records, up to the first bad frame.
  std::uint64_t at = kHeaderBytes;
  std::string bad;
  std::vector<std::uint8_t> payload;
  while (at < file_size) {
    std::array<std::uint8_t, kFrameBytes> frame{};
    if (file_size - at < kFrameBytes || !read_at(fd_.get(), at, frame.data(), frame.size(), path_)) {
      bad = "a frame cut short";
      break;
    }
    const std::uint32_t length = get_u32(frame.data());
    const std::uint32_t crc = get_u32(frame.data() + 4);
    const std::uint8_t kind = frame[8];
    if (length > kMaxRecordBytes || length > file_size - at - kFrameBytes) {
      bad = "a record of " + std::to_string(length) + " bytes beyond the end of the file";
      break;
    }
    payload.resize(length);
    if (!read_at(fd_.get(), at + kFrameBytes, payload.data(), length, path_)) {
      bad = "a record cut short";
      break;
    }
    if (checksum(kind, payload.data(), payload.size()) != crc) {
      bad = "a checksum mismatch";
      break;
    }
    if (!known_kind(kind)) {
      bad = "an unknown record kind " + std::to_string(kind);
      break;
    }
    index_.push_back(RecordRef{segment, at, length, static_cast<RecordKind>(kind)});
    ++records_;
    at += kFrameBytes + length;
  }
  if (at < file_size) {
    if (!last) {
      throw JournalError("journal segment '" + path_ + "' is corrupt at offset " + std::to_string(at) + " (" + bad +
                         ") but later segments exist: not recovered (move the directory away to start anew)");
    }
    cut_bytes_ += file_size - at;
    logger()->warn("journal '{}': cut {} byte(s) after record {} at offset {} ({}): a torn or corrupt tail, not applied",
                   path_, file_size - at, records_, at, bad);
    if (::ftruncate(fd_.get(), static_cast<off_t>(at)) != 0) fail("cannot cut journal '" + path_ + "'", errno);
    if (::fsync(fd_.get()) != 0) fail("cannot fsync journal '" + path_ + "'", errno);
  }
  size_ = at;
}

JournalLog::~JournalLog() = default;

std::uint64_t JournalLog::bytes() const {
  std::uint64_t n = size_;
  for (const auto& [k, size] : older_) n += size;
  return n;
}

std::vector<std::uint8_t> JournalLog::payload(std::size_t i) const {
  const RecordRef& r = index_.at(i);
  const std::string path = segment_path(dir_, r.segment);
  UniqueFd own;
  int fd = fd_.get();
  if (r.segment != segment_) {
    own = UniqueFd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (own.get() < 0) fail("cannot open journal '" + path + "'", errno);
    fd = own.get();
  }
  std::vector<std::uint8_t> out(r.length);
  if (!read_at(fd, r.offset + kFrameBytes, out.data(), out.size(), path)) {
    throw JournalError("journal '" + path + "' is shorter than when it was opened");
  }
  return out;
}

void JournalLog::read(std::size_t from,
                      const std::function<void(RecordKind, const std::vector<std::uint8_t>&)>& on_record) const {
  for (std::size_t i = from; i < index_.size(); ++i) on_record(index_[i].kind, payload(i));
}

void JournalLog::sync_dir() { journal::sync_dir(dir_fd_.get(), dir_); }

void JournalLog::create_segment(const std::string& dir, int dir_fd, std::uint64_t segment) {
  const std::string path = segment_path(dir, segment);
  UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600));
  if (fd.get() < 0) fail("cannot create journal segment '" + path + "'", errno);
  try {
    const std::array<std::uint8_t, kHeaderBytes> header = new_header();
    journal::write_all(fd.get(), header.data(), header.size(), "cannot append to journal '" + path + "'");
    if (::fdatasync(fd.get()) != 0) fail("cannot fdatasync journal '" + path + "'", errno);
    journal::sync_dir(dir_fd, dir);  // its entry is durable before any record in it is acknowledged
  } catch (...) {
    ::unlink(path.c_str());
    throw;
  }
}

void JournalLog::start_segment(std::uint64_t segment, bool created) {
  if (segment <= segment_) throw JournalError("journal segment " + std::to_string(segment) + " is not new");
  std::string path = segment_path(dir_, segment);
  // The file holding a new segment's header alone, or an invalid descriptor.
  auto open_new = [&] {
    UniqueFd fd(::open(path.c_str(), O_RDWR | O_CLOEXEC));
    struct stat st {};
    std::array<std::uint8_t, kHeaderBytes> header{};
    if (fd.get() < 0 || ::fstat(fd.get(), &st) != 0 || static_cast<std::uint64_t>(st.st_size) != kHeaderBytes ||
        !read_at(fd.get(), 0, header.data(), header.size(), path) || header != new_header()) {
      return UniqueFd();
    }
    return fd;
  };
  UniqueFd fd = created ? open_new() : UniqueFd();
  if (fd.get() < 0) {
    if (created) ::unlink(path.c_str());  // not what was created ahead: made again
    create_segment(dir_, dir_fd_.get(), segment);
    fd = open_new();
    if (fd.get() < 0) throw JournalError("journal segment '" + path + "' cannot be opened after it was created");
  }
  older_[segment_] = size_;
  std::swap(fd_, fd);
  path_ = std::move(path);
  segment_ = segment;
  size_ = kHeaderBytes;
}

std::vector<std::string> JournalLog::forget_segments_before(std::uint64_t segment) {
  segment = std::min(segment, segment_);
  std::vector<std::string> paths;
  for (auto it = older_.begin(); it != older_.end() && it->first < segment;) {
    paths.push_back(segment_path(dir_, it->first));
    it = older_.erase(it);
  }
  if (!paths.empty()) first_ = older_.empty() ? segment_ : older_.begin()->first;
  return paths;
}

void JournalLog::append(RecordKind kind, const std::vector<std::uint8_t>& payload) {
  if (payload.size() > kMaxRecordBytes) {
    throw JournalError("journal record of " + std::to_string(payload.size()) + " bytes exceeds the limit of " +
                       std::to_string(kMaxRecordBytes));
  }
  std::array<std::uint8_t, kFrameBytes> frame{};
  const auto k = static_cast<std::uint8_t>(kind);
  put_u32(frame.data(), static_cast<std::uint32_t>(payload.size()));
  put_u32(frame.data() + 4, checksum(k, payload.data(), payload.size()));
  frame[8] = k;
  // pwrite at the known end: a failed append leaves `size_` at the last intact record, and the
  // next append overwrites the partial one.
  const std::uint64_t at = size_;
  auto write_at = [&](std::uint64_t offset, const std::uint8_t* data, std::size_t size) {
    while (size > 0) {
      const ssize_t n = ::pwrite(fd_.get(), data, size, static_cast<off_t>(offset));
      if (n < 0) {
        if (errno == EINTR) continue;
        fail("cannot append to journal '" + path_ + "'", errno);
      }
      data += n;
      offset += static_cast<std::uint64_t>(n);
      size -= static_cast<std::size_t>(n);
    }
  };
  write_at(at, frame.data(), frame.size());
  write_at(at + kFrameBytes, payload.data(), payload.size());
  size_ = at + kFrameBytes + payload.size();
  ++records_;
}

void JournalLog::sync() {
  if (::fdatasync(fd_.get()) != 0) fail("cannot fdatasync journal '" + path_ + "'", errno);
}

}  // namespace surfeledit::service
