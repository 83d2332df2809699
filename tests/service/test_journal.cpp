// The journal's log framing (torn and corrupt tails cut at every byte of the last record) and the
// request records' CDR round trip.
#include <gtest/gtest.h>

#include <dds/dds.h>
#include <fcntl.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "../../server/service/src/journal_records.hpp"
#include "surfeledit/service/decode.hpp"
#include "surfeledit/service/journal.hpp"

namespace fs = std::filesystem;
using surfeledit::service::JournalError;
using surfeledit::service::JournalLog;
using surfeledit::service::RecordKind;

namespace {

using Payload = std::vector<std::uint8_t>;

// A fresh directory below the system's temporary directory, removed afterwards.
struct TempDir {
  TempDir() {
    path = fs::temp_directory_path() / ("surfeledit-journal-test-" + std::to_string(::getpid()) + "-" +
                                        std::to_string(counter++));
    fs::remove_all(path);
  }
  ~TempDir() { fs::remove_all(path); }
  fs::path path;
  static inline int counter = 0;
};

// Every record of the log in `dir` (opening it cuts a bad tail).
std::vector<std::pair<RecordKind, Payload>> read_all(const fs::path& dir) {
  std::vector<std::pair<RecordKind, Payload>> out;
  JournalLog log(dir.string(), [&](RecordKind k, const Payload& p) { out.emplace_back(k, p); });
  return out;
}

// Records of sizes that cross the interesting boundaries (empty, a few bytes, a few KB).
std::vector<Payload> sample_payloads() {
  std::mt19937 gen(11);
  std::vector<Payload> out;
  for (std::size_t size : {0u, 1u, 7u, 300u, 4096u, 33u}) {
    Payload p(size);
    for (auto& b : p) b = static_cast<std::uint8_t>(gen());
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<std::uint8_t> file_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

TEST(JournalLog, RecordsComeBackInOrder) {
  TempDir dir;
  const auto payloads = sample_payloads();
  {
    JournalLog log(dir.path.string(), [](RecordKind, const Payload&) { FAIL() << "a new log has no records"; });
    for (std::size_t i = 0; i < payloads.size(); ++i) {
      log.append(i % 2 ? RecordKind::Refusal : RecordKind::Request, payloads[i]);
    }
    log.sync();
  }
  const auto got = read_all(dir.path);
  ASSERT_EQ(got.size(), payloads.size());
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    EXPECT_EQ(got[i].first, i % 2 ? RecordKind::Refusal : RecordKind::Request);
    EXPECT_EQ(got[i].second, payloads[i]) << "record " << i;
  }
}

TEST(JournalLog, SecondServerOnTheSameDirectoryIsRefused) {
  TempDir dir;
  JournalLog first(dir.path.string(), [](RecordKind, const Payload&) {});
  EXPECT_THROW(JournalLog(dir.path.string(), [](RecordKind, const Payload&) {}), JournalError);
}

TEST(JournalLog, NotAJournalIsAnError) {
  TempDir dir;
  fs::create_directories(dir.path);
  write_bytes(dir.path / "journal.log", std::vector<std::uint8_t>(64, 'x'));
  EXPECT_THROW(read_all(dir.path), JournalError);
  // A path below a regular file cannot be created.
  EXPECT_THROW(read_all(dir.path / "journal.log" / "sub"), JournalError);
}

// The header's record format (journal.hpp kRecordFormat): a log written by this server carries it; one of
// another record format (0: before the header held it, or a later one) is refused and left as it was.
TEST(JournalLog, OtherRecordFormatIsRefused) {
  TempDir dir;
  { JournalLog log(dir.path.string(), [](RecordKind, const Payload&) {}); }
  std::vector<std::uint8_t> bytes = file_bytes(dir.path / "journal.log");
  ASSERT_EQ(bytes.size(), 16u);
  EXPECT_EQ(bytes[12], surfeledit::service::kRecordFormat);
  for (std::uint8_t other : {std::uint8_t{0}, static_cast<std::uint8_t>(surfeledit::service::kRecordFormat + 1)}) {
    bytes[12] = other;
    write_bytes(dir.path / "journal.log", bytes);
    try {
      read_all(dir.path);
      ADD_FAILURE() << "record format " << int(other) << " was read";
    } catch (const JournalError& e) {
      EXPECT_NE(std::string(e.what()).find("records of format " + std::to_string(other)), std::string::npos) << e.what();
    }
    EXPECT_EQ(file_bytes(dir.path / "journal.log"), bytes);
  }
}

// Truncating the file at every byte of the last record, or flipping any bit of it, loses exactly
// that record; the ones before come back intact and the log accepts appends again.
TEST(JournalLog, TornOrCorruptLastRecordIsCutAtEveryPosition) {
  TempDir dir;
  const auto payloads = sample_payloads();
  {
    JournalLog log(dir.path.string(), [](RecordKind, const Payload&) {});
    for (const auto& p : payloads) log.append(RecordKind::Request, p);
    log.sync();
  }
  const fs::path file = dir.path / "journal.log";
  const std::vector<std::uint8_t> whole = file_bytes(file);
  const std::size_t last_size = 9 + payloads.back().size();  // frame + payload
  const std::size_t last_start = whole.size() - last_size;
  auto expect_all_but_last = [&](const std::string& what) {
    const auto got = read_all(dir.path);
    ASSERT_EQ(got.size(), payloads.size() - 1) << what;
    for (std::size_t i = 0; i + 1 < payloads.size(); ++i) ASSERT_EQ(got[i].second, payloads[i]) << what;
    ASSERT_EQ(fs::file_size(file), last_start) << what << ": the tail is cut off the file";
  };
  for (std::size_t cut = last_start; cut < whole.size(); ++cut) {
    write_bytes(file, std::vector<std::uint8_t>(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(cut)));
    expect_all_but_last("truncated at " + std::to_string(cut));
  }
  for (std::size_t at = last_start; at < whole.size(); ++at) {
    for (int bit : {0, 7}) {
      std::vector<std::uint8_t> flipped = whole;
      flipped[at] ^= static_cast<std::uint8_t>(1u << bit);
      write_bytes(file, flipped);
      expect_all_but_last("bit " + std::to_string(bit) + " flipped at " + std::to_string(at));
    }
  }
  // Garbage after the last intact record (a torn append of another record) is cut as well.
  std::vector<std::uint8_t> garbage = whole;
  garbage.insert(garbage.end(), {0xff, 0xff, 0xff, 0x7f, 1, 2, 3, 4, 1, 9, 9});
  write_bytes(file, garbage);
  EXPECT_EQ(read_all(dir.path).size(), payloads.size());
  EXPECT_EQ(fs::file_size(file), whole.size());
  // After a cut the log appends where the intact records end.
  write_bytes(file, std::vector<std::uint8_t>(whole.begin(), whole.end() - 3));
  {
    JournalLog log(dir.path.string(), [](RecordKind, const Payload&) {});
    log.append(RecordKind::Expiry, Payload{1, 2, 3});
    log.sync();
  }
  const auto got = read_all(dir.path);
  ASSERT_EQ(got.size(), payloads.size());
  EXPECT_EQ(got.back().first, RecordKind::Expiry);
  EXPECT_EQ(got.back().second, (Payload{1, 2, 3}));
}

// A request sample survives the journal's CDR form field by field (strings, sequences of structs).
TEST(JournalRecords, RequestCdrRoundTrip) {
  namespace j = surfeledit::service::journal;
  surfeledit_proto_Request r{};
  r.client_id = dds_string_dup("client-α");
  r.request_id = 0x1234567890abcdefULL;
  r.session = dds_string_dup("s1");
  r.op = surfeledit_proto_OP_DEFORM;
  r.token = dds_string_dup("");
  surfeledit_proto_Deform d{};
  d.translation.x = 0.25;
  d.translation.y = -1e-300;
  d.translation.z = 3.0;
  d.axis.z = 1.0;
  d.angle = 0.125;
  d.has_center = true;
  d.center.x = 7.0;
  d.blend = dds_string_dup("quadratic");
  r.deform._buffer = &d;
  r.deform._length = r.deform._maximum = 1;
  std::vector<std::uint8_t> cdr = j::request_cdr(r);
  j::RequestSample back(cdr);
  const surfeledit_proto_Request& b = back.get();
  EXPECT_STREQ(b.client_id, "client-α");
  EXPECT_EQ(b.request_id, r.request_id);
  EXPECT_STREQ(b.session, "s1");
  EXPECT_EQ(b.op, surfeledit_proto_OP_DEFORM);
  ASSERT_EQ(b.deform._length, 1u);
  EXPECT_EQ(b.deform._buffer[0].translation.y, -1e-300);
  EXPECT_EQ(b.deform._buffer[0].translation.z, 3.0);
  EXPECT_EQ(b.deform._buffer[0].angle, 0.125);
  EXPECT_TRUE(b.deform._buffer[0].has_center);
  EXPECT_EQ(b.deform._buffer[0].center.x, 7.0);
  EXPECT_STREQ(b.deform._buffer[0].blend, "quadratic");
  EXPECT_EQ(b.load_chunk._length, 0u);
  // The decoded command is the one the live request decodes to.
  const auto live = surfeledit::service::decode(r);
  const auto replayed = surfeledit::service::decode(b);
  EXPECT_EQ(live.client_id, replayed.client_id);
  EXPECT_EQ(live.op, replayed.op);
  // A cut CDR is refused, not read past its end.
  for (std::size_t n : {std::size_t(0), std::size_t(4), cdr.size() / 2, cdr.size() - 1}) {
    EXPECT_THROW(j::RequestSample(std::vector<std::uint8_t>(cdr.begin(), cdr.begin() + static_cast<std::ptrdiff_t>(n))),
                 JournalError)
        << n;
  }
  dds_free(r.client_id);
  dds_free(r.session);
  dds_free(r.token);
  dds_free(d.blend);
}

TEST(JournalRecords, RefusalAndExpiryRoundTrip) {
  namespace j = surfeledit::service::journal;
  j::RefusalRecord r{"c", 42, 9, surfeledit::service::Status::Conflict, "deform.expect_version", "moved on", 17};
  const j::RefusalRecord b = j::decode_refusal(j::encode(r));
  EXPECT_EQ(b.client_id, "c");
  EXPECT_EQ(b.request_id, 42u);
  EXPECT_EQ(b.request_op, 9u);
  EXPECT_EQ(b.status, surfeledit::service::Status::Conflict);
  EXPECT_EQ(b.field, "deform.expect_version");
  EXPECT_EQ(b.message, "moved on");
  EXPECT_EQ(b.version, 17u);
  for (const auto kind : {surfeledit::service::Expiry::Kind::Lease, surfeledit::service::Expiry::Kind::Grace,
                          surfeledit::service::Expiry::Kind::Forget}) {
    const j::ExpiryRecord e = j::decode_expiry(j::encode(j::ExpiryRecord{{kind, "gone"}}));
    EXPECT_EQ(e.expiry.kind, kind);
    EXPECT_EQ(e.expiry.name, "gone");
  }
  auto bad = j::encode(j::ExpiryRecord{{surfeledit::service::Expiry::Kind::Lease, "x"}});
  bad[0] = 7;  // no such kind
  EXPECT_THROW(j::decode_expiry(bad), JournalError);
  auto payload = j::encode(r);
  payload.pop_back();
  EXPECT_THROW(j::decode_refusal(payload), JournalError);
}

// Segments (docs/journal.md "Snapshots"): a new segment starts with its header alone; the log reads the
// kept segments in order as one sequence; older ones are forgotten (and their files handed back for
// deletion) on request; a gap between segments, a newest segment without a record, and a corrupt segment
// that is not the last are handled as documented.
TEST(JournalLog, SegmentsReadInOrderAndOldOnesAreDropped) {
  TempDir dir;
  const auto payloads = sample_payloads();
  {
    JournalLog log(dir.path.string());
    log.append(RecordKind::Request, payloads[0]);
    log.sync();
    log.start_segment(1);
    log.append(RecordKind::Snapshot, payloads[1]);
    log.append(RecordKind::Request, payloads[2]);
    log.sync();
    log.start_segment(2);
    log.append(RecordKind::Snapshot, payloads[3]);
    log.append(RecordKind::Refusal, payloads[4]);
    log.sync();
    EXPECT_EQ(log.segment(), 2u);
    EXPECT_EQ(log.bytes(), fs::file_size(dir.path / "journal.log") + fs::file_size(dir.path / "journal-1.log") +
                               fs::file_size(dir.path / "journal-2.log"));
  }
  auto got = read_all(dir.path);
  ASSERT_EQ(got.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(got[i].second, payloads[i]) << i;
  EXPECT_EQ(got[1].first, RecordKind::Snapshot);
  {
    JournalLog log(dir.path.string());
    EXPECT_EQ(log.index().size(), 5u);
    EXPECT_EQ(log.index()[3].segment, 2u);
    EXPECT_EQ(log.payload(2), payloads[2]);
    const std::vector<std::string> doomed = log.forget_segments_before(1);
    ASSERT_EQ(doomed.size(), 1u);
    EXPECT_EQ(doomed[0], JournalLog::segment_path(dir.path.string(), 0));
    EXPECT_EQ(log.first_segment(), 1u);
    EXPECT_EQ(log.bytes(), fs::file_size(dir.path / "journal-1.log") + fs::file_size(dir.path / "journal-2.log"));
    fs::remove(doomed[0]);
  }
  EXPECT_FALSE(fs::exists(dir.path / "journal.log"));
  got = read_all(dir.path);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].second, payloads[1]);
  // A newest segment without its first record (cut while it was started) is removed; appends go before it.
  {
    std::vector<std::uint8_t> header = file_bytes(dir.path / "journal-2.log");
    header.resize(16);
    write_bytes(dir.path / "journal-3.log", header);
    JournalLog log(dir.path.string());
    EXPECT_EQ(log.segment(), 2u);
    EXPECT_EQ(log.index().size(), 4u);
  }
  EXPECT_FALSE(fs::exists(dir.path / "journal-3.log"));
  // A corrupt segment before the last one is an error, never skipped.
  std::vector<std::uint8_t> middle = file_bytes(dir.path / "journal-1.log");
  middle.back() ^= 1;
  write_bytes(dir.path / "journal-1.log", middle);
  EXPECT_THROW(read_all(dir.path), JournalError);
  // A gap between segments (2, then 4) is an error too.
  fs::remove(dir.path / "journal-1.log");
  fs::copy_file(dir.path / "journal-2.log", dir.path / "journal-4.log");
  EXPECT_THROW(read_all(dir.path), JournalError);
}

// A segment created ahead for the next snapshot (JournalLog::create_segment: its header alone) is dropped
// when the log is opened, before the segment before it is judged: that one's torn tail is then the last
// segment's and is cut (not an error), and appends go there. start_segment adopts a file created ahead
// and makes one again in place of a file that is not a new header.
TEST(JournalLog, SegmentCreatedAheadIsDroppedAtOpenAndTheTornTailBeforeItIsCut) {
  TempDir dir;
  const auto payloads = sample_payloads();
  {
    JournalLog log(dir.path.string());
    log.append(RecordKind::Request, payloads[3]);
    log.append(RecordKind::Request, payloads[4]);
    log.sync();
    JournalLog::create_segment(dir.path.string(), log.dir_fd(), 1);
    EXPECT_EQ(fs::file_size(dir.path / "journal-1.log"), 16u);
  }
  std::vector<std::uint8_t> bytes = file_bytes(dir.path / "journal.log");
  bytes.resize(bytes.size() - 3);  // the second record torn
  write_bytes(dir.path / "journal.log", bytes);
  {
    JournalLog log(dir.path.string());
    EXPECT_EQ(log.segment(), 0u);
    ASSERT_EQ(log.index().size(), 1u);
    EXPECT_GT(log.cut_bytes(), 0u);
    EXPECT_FALSE(fs::exists(dir.path / "journal-1.log"));
    // Adopted when created ahead; made again when the file there is not a new segment's header alone.
    JournalLog::create_segment(dir.path.string(), log.dir_fd(), 1);
    log.start_segment(1, true);
    log.append(RecordKind::Refusal, payloads[1]);
    log.sync();
    write_bytes(dir.path / "journal-2.log", {1, 2, 3});
    log.start_segment(2, true);
    log.append(RecordKind::Expiry, payloads[2]);
    log.sync();
  }
  const auto got = read_all(dir.path);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].second, payloads[3]);
  EXPECT_EQ(got[1].first, RecordKind::Refusal);
  EXPECT_EQ(got[2].first, RecordKind::Expiry);
  EXPECT_EQ(got[2].second, payloads[2]);
}
