// The journal's snapshot files (docs/journal.md "Snapshots"): DIR/snapshot-<seq>.bin holds the
// handler's whole state (Handler::Snapshot, encoded on the writer thread) after every record before the
// Snapshot record that names it.
// A 32-byte header (magic "SESNAPSH", u32 file format 1, u32 record format kRecordFormat, u64 seq,
// u64 payload bytes), then the payload; the Snapshot record holds the whole file's size and CRC-32,
// so a file that does not match its record (torn, corrupt, replaced) is never restored. Written
// under a temporary name, fdatasynced, renamed, and the directory fsynced. Private to the service.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "journal_io.hpp"
#include "journal_records.hpp"
#include "surfeledit/service/journal.hpp"

namespace surfeledit::service::journal {

std::string snapshot_path(const std::string& dir, std::uint64_t seq);

// Where the time of write_snapshot_file went, ms.
struct SnapshotFileTimes {
  double write_ms = 0.0;  // creating the temporary file and writing it (CRC included)
  double sync_ms = 0.0;   // its fdatasync, the rename and the directory's fsync
};

// Writes snapshot `seq` holding the concatenation of `parts` durably into `dir` (open as `dir_fd`):
// `.tmp`, fdatasync, rename, directory fsync; returns its Snapshot record (records = 0, for the caller).
// Removes what it wrote on failure. Throws JournalError.
SnapshotRecord write_snapshot_file(const std::string& dir, int dir_fd, std::uint64_t seq,
                                   const std::vector<std::string>& parts, SnapshotFileTimes* times = nullptr);

// The file `record` names, checked against the record and its header; its payload starts at
// kSnapshotHeaderBytes. Throws JournalError saying what is wrong (missing, size, checksum, header).
std::string read_snapshot_file(const std::string& dir, const SnapshotRecord& record);
constexpr std::size_t kSnapshotHeaderBytes = 32;

// Removes the snapshot files numbered below `seq` and every temporary one (never complete after a crash;
// call only while no snapshot is being written), then fsyncs the directory. Throws JournalError.
void remove_snapshots_before(const std::string& dir, int dir_fd, std::uint64_t seq);

}  // namespace surfeledit::service::journal
