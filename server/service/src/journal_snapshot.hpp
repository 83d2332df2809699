// The journal's snapshot files (docs/journal.md "Snapshots"): DIR/snapshot-<seq>.bin holds the
// handler's whole state (Handler::save) after every record before the Snapshot record that names it.
// A 32-byte header (magic "SESNAPSH", u32 file format 1, u32 record format kRecordFormat, u64 seq,
// u64 payload bytes), then the payload; the Snapshot record holds the whole file's size and CRC-32,
// so a file that does not match its record (torn, corrupt, replaced) is never restored. Written
// under a temporary name, fdatasynced, renamed, and the directory fsynced. Private to the service.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "journal_records.hpp"
#include "surfeledit/service/journal.hpp"

namespace surfeledit::service::journal {

// CRC-32 (zlib) of `size` bytes continuing `crc` (0 to start); any size.
std::uint32_t crc32_of(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

// Writes all `size` bytes to `fd`, again after a short write or EINTR; throws JournalError "<what>: <error>".
void write_all(int fd, const std::uint8_t* data, std::size_t size, const std::string& what);

std::string snapshot_path(const std::string& dir, std::uint64_t seq);

// Writes snapshot `seq` holding the concatenation of `parts` durably (its directory entry too, through
// `log`); returns its Snapshot record (records = 0, for the caller). Removes what it wrote on failure.
// Throws JournalError.
SnapshotRecord write_snapshot_file(JournalLog& log, std::uint64_t seq, const std::vector<std::string>& parts);

// The file `record` names, checked against the record and its header; its payload starts at
// kSnapshotHeaderBytes. Throws JournalError saying what is wrong (missing, size, checksum, header).
std::string read_snapshot_file(const std::string& dir, const SnapshotRecord& record);
constexpr std::size_t kSnapshotHeaderBytes = 32;

// Removes the snapshot files numbered below `seq` (and temporary files left by a crash). Throws JournalError.
void remove_snapshots_before(JournalLog& log, std::uint64_t seq);

}  // namespace surfeledit::service::journal
