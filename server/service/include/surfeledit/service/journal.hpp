// The journal (surfeledit-server --journal DIR, PROTOCOL.md "Journal"): an append-only log of
// the requests the server accepted, in the server's order, made durable before their replies are
// written. On start the service replays it through the same Handler::handle path (the core is
// deterministic), which restores every session, its history and versions, and the replies kept for
// repeated request ids. Periodic snapshots (JournalConfig::snapshot_records / snapshot_mb) bound that
// replay: recovery restores the newest one and replays only the records after it.
//
// This header holds the settings, the typed error and the log file's framing (JournalLog); what a
// record holds and how it is replayed is private to the service (src/journal_*.hpp).
// Standard library only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace surfeledit::service {

// When a record is forced to disk (fdatasync) relative to its reply.
enum class JournalSync {
  Op,     // every record before its reply is written (one fdatasync per accepted op)
  Group,  // group commit: the records of `group_ms` share one fdatasync; their replies wait for it
};

struct JournalConfig {
  std::string dir;                    // journal directory (created if missing); empty: no journal
  JournalSync sync = JournalSync::Op;  // durability policy
  std::uint32_t group_ms = 5;         // JournalSync::Group: the longest a reply waits for its group's fsync, ms
  // After recovery, how long a recovered client may take to send its first request before it is
  // detached like a client whose lease ran out, ms (a client notices a dead server in ~1.5 s).
  std::uint64_t rejoin_ms = 10'000;
  // Snapshots (docs/journal.md): one is taken, and a new log segment started, once this many records
  // were journaled since the last one (0: never by count) ...
  std::uint64_t snapshot_records = 0;
  // ... or once the log segment since the last one holds more than this many MiB (0: never by size).
  std::uint64_t snapshot_mb = 0;
};

// The journal directory cannot be used (not creatable, not writable, locked by another server,
// not a journal, or its records do not replay to what they recorded). The server exits with
// kJournalExitCode on it.
class JournalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The format of the records (the header's second version): what a Request record's CDR holds (the IDL's
// Request as of this server), the other records' layouts and where they stand. Bumped whenever one
// changes (a field added to a request type changes the CDR); a journal of a format outside
// kOldestRecordFormat..kRecordFormat is refused (JournalError) rather than replayed wrongly. 0: journals
// written before the header held it (before the blend / fill_holes `projection` field was journaled
// alike). 1: snapshot k's record is the first record of segment k. 2: snapshot k is the state at the
// start of segment k and its record follows anywhere in segment k, once its file is durable (written
// off the request thread); format 1 is the special case of 2 where the record comes first, so both read.
constexpr std::uint32_t kRecordFormat = 2;
constexpr std::uint32_t kOldestRecordFormat = 1;  // the oldest record format this server reads

// Exit code of surfeledit-server when the journal cannot be used.
constexpr int kJournalExitCode = 3;

// Kinds of records (the first byte of each record).
enum class RecordKind : std::uint8_t {
  Request = 1,  // an accepted request: its CDR form and what its reply said
  Refusal = 2,  // a refused request's reply (kept for repeats; replay does not re-run it)
  Expiry = 3,   // a lease or grace period that ran out (Handler::expire_leases, apply_expiry)
  Snapshot = 4,  // snapshot k's file is durable: the state at the start of segment k (a record in segment k)
};

// Owns a file descriptor (closed on destruction). Move-only.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  ~UniqueFd();
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  UniqueFd& operator=(UniqueFd&& other) noexcept;
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_ = -1;
};

// The log: segments DIR/journal.log (segment 0) and DIR/journal-<k>.log (k = 1, 2, ...; segment k
// starts where snapshot k was taken and holds its Snapshot record once its file is durable), read in order as one sequence of records. Each
// segment has a 16-byte header (magic "SEJOURNL", u32 framing format 1, u32 record format
// kRecordFormat, 4 reserved bytes), then records framed as
//   u32 payload length | u32 CRC-32 (zlib) of kind and payload | u8 kind | payload
// (little endian). Opening it indexes every intact record and cuts a torn or corrupt tail of the
// last segment (a short frame, a length beyond the file or kMaxRecordBytes, a checksum mismatch, an
// unknown kind) with a log line: what follows the first bad frame is never applied. A bad frame in a
// segment that is not the last, or a gap in the numbers, is a JournalError (never skipped). The
// directory is locked (flock) while the log is open. One thread uses it (create_segment: any).
class JournalLog {
 public:
  static constexpr std::uint32_t kMaxRecordBytes = std::uint32_t(1) << 30;  // largest payload accepted

  // Where one intact record is.
  struct RecordRef {
    std::uint64_t segment = 0;  // segment number
    std::uint64_t offset = 0;   // of its frame in the segment file
    std::uint32_t length = 0;   // payload bytes
    RecordKind kind = RecordKind::Request;
  };

  // Opens (creating) the log in `dir` and indexes its intact records (cutting a torn tail); appends
  // go to the last segment. Throws JournalError.
  explicit JournalLog(const std::string& dir);
  // The same, then hands every record to `on_record` in order (read(0, on_record)).
  JournalLog(const std::string& dir, const std::function<void(RecordKind, const std::vector<std::uint8_t>&)>& on_record);
  ~JournalLog();
  JournalLog(const JournalLog&) = delete;
  JournalLog& operator=(const JournalLog&) = delete;

  // The intact records found at open, in order.
  const std::vector<RecordRef>& index() const { return index_; }
  // The payload of index()[i] (read again from its segment). Throws JournalError.
  std::vector<std::uint8_t> payload(std::size_t i) const;
  // Hands the records index()[from..] to `on_record` in order (an exception from it propagates).
  void read(std::size_t from, const std::function<void(RecordKind, const std::vector<std::uint8_t>&)>& on_record) const;

  // Appends one record (written to the file, not yet forced to disk). Throws JournalError.
  void append(RecordKind kind, const std::vector<std::uint8_t>& payload);
  // Forces everything appended to disk (fdatasync). Throws JournalError.
  void sync();
  // Starts segment `segment` (> the current one), its header and directory entry durable; later appends
  // go there. Sync the current segment first (its unsynced records are not synced by later syncs).
  // `created`: create_segment() made its file already (it is checked), else it is created here. On failure
  // appends stay in the current segment. Throws JournalError.
  void start_segment(std::uint64_t segment, bool created = false);
  // Creates segment `segment`'s file in `dir` (open as `dir_fd`) holding its header, durable with its
  // directory entry; removed on failure. Any thread (the journal's writer thread creates the next one
  // ahead; a newest segment holding only its header is removed when the log is opened). Throws JournalError.
  static void create_segment(const std::string& dir, int dir_fd, std::uint64_t segment);
  // Forgets the segments numbered below `segment` (never the current one) and returns their files, oldest
  // first, for the caller to delete in that order (the journal's writer thread does).
  std::vector<std::string> forget_segments_before(std::uint64_t segment);
  // Forces the directory's entries to disk (fsync). Throws JournalError.
  void sync_dir();

  std::uint64_t records() const { return records_; }          // intact records read plus appended
  std::uint64_t bytes() const;                                // size of every segment (headers included)
  std::uint64_t segment() const { return segment_; }          // the segment appends go to
  std::uint64_t first_segment() const { return first_; }      // the oldest segment kept
  std::uint64_t segment_bytes() const { return size_; }       // size of the current segment
  std::uint64_t cut_bytes() const { return cut_bytes_; }      // bytes of torn / corrupt tail cut at open
  const std::string& path() const { return path_; }           // the current segment
  const std::string& dir() const { return dir_; }
  int dir_fd() const { return dir_fd_.get(); }                // the directory, open (for its fsyncs)

  // The file of segment `segment` in `dir`.
  static std::string segment_path(const std::string& dir, std::uint64_t segment);

 private:
  // Indexes the records of segment `segment` (`last`: the newest; its torn tail is cut).
  void scan(std::uint64_t segment, bool last);

  std::string dir_;
  std::string path_;
  UniqueFd dir_fd_;  // the directory (locked with flock; fsynced after the log was created)
  UniqueFd fd_;      // the current segment, open for reading and appending
  std::uint64_t segment_ = 0;
  std::uint64_t first_ = 0;
  std::uint64_t size_ = 0;
  std::map<std::uint64_t, std::uint64_t> older_;  // sizes of the kept segments before the current one
  std::uint64_t records_ = 0;
  std::uint64_t cut_bytes_ = 0;
  std::vector<RecordRef> index_;
};

}  // namespace surfeledit::service
