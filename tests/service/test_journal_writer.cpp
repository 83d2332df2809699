// The journal's writer thread (journal_writer.hpp, docs/journal.md "Snapshots: the writer thread"): a
// snapshot's result arrives only once its file is durable under its final name, with a record whose size and
// CRC match the file (checked here with zlib directly); one snapshot in flight at a time; a failed write
// reports why and leaves no file; removal deletes what it is given and the older and temporary snapshots;
// the destructor finishes the queue.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "../../server/service/src/journal_writer.hpp"

namespace fs = std::filesystem;
using surfeledit::service::JournalError;
using surfeledit::service::journal::SnapshotThread;
using surfeledit::service::journal::WrittenSnapshot;

namespace {

struct Dir {
  Dir() {
    path = fs::temp_directory_path() / ("surfeledit-writer-test-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~Dir() { fs::remove_all(path); }
  fs::path path;
};

// Counts the thread's wake-ups and waits for the next one.
struct Wakes {
  std::mutex mutex;
  std::condition_variable cv;
  int count = 0;
  void wake() {
    std::lock_guard<std::mutex> lock(mutex);
    ++count;
    cv.notify_all();
  }
  bool wait_for(int n) {
    std::unique_lock<std::mutex> lock(mutex);
    return cv.wait_for(lock, std::chrono::seconds(60), [&] { return count >= n; });
  }
};

std::string file_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void touch(const fs::path& p) { std::ofstream(p) << "x"; }

std::vector<std::string> sample_parts() {
  std::mt19937 gen(3);
  std::string big(1 << 20, '\0');
  for (char& c : big) c = static_cast<char>(gen());
  return {"first part", big, "", "last"};
}

}  // namespace

TEST(JournalSnapshotThread, ResultOnlyOnceTheFileIsDurableOneInFlightFailuresAndRemoval) {
  Dir dir;
  Wakes wakes;
  SnapshotThread thread(dir.path.string(), [&] { wakes.wake(); });
  const std::vector<std::string> parts = sample_parts();
  std::string payload;
  for (const std::string& p : parts) payload += p;

  EXPECT_FALSE(thread.busy());
  EXPECT_FALSE(thread.take_written().has_value());
  thread.write(1, parts);
  EXPECT_TRUE(thread.busy());
  EXPECT_THROW(thread.write(2, parts), JournalError);  // one in flight
  ASSERT_TRUE(wakes.wait_for(1));
  // Woken: the file is there under its final name, complete, and the temporary one is gone.
  const fs::path file = dir.path / "snapshot-1.bin";
  ASSERT_TRUE(fs::exists(file));
  EXPECT_FALSE(fs::exists(dir.path / "snapshot-1.bin.tmp"));
  std::optional<WrittenSnapshot> done = thread.take_written();
  ASSERT_TRUE(done.has_value());
  EXPECT_FALSE(thread.busy());
  EXPECT_TRUE(done->error.empty()) << done->error;
  EXPECT_EQ(done->seq, 1u);
  const std::string bytes = file_text(file);
  EXPECT_EQ(done->record.seq, 1u);
  EXPECT_EQ(done->record.file_bytes, bytes.size());
  EXPECT_EQ(done->record.file_crc,
            crc32(0, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
  EXPECT_EQ(bytes.substr(32), payload);
  EXPECT_GE(done->times.write_ms, 0.0);
  EXPECT_GE(done->times.sync_ms, 0.0);

  // A write that fails (a directory where its temporary file goes): reported, no file, not in flight.
  fs::create_directory(dir.path / "snapshot-2.bin.tmp");
  thread.write(2, parts);
  ASSERT_TRUE(wakes.wait_for(2));
  done = thread.take_written();
  ASSERT_TRUE(done.has_value());
  EXPECT_NE(done->error.find("snapshot-2.bin.tmp"), std::string::npos) << done->error;
  EXPECT_FALSE(fs::exists(dir.path / "snapshot-2.bin"));
  EXPECT_FALSE(thread.busy());
  fs::remove(dir.path / "snapshot-2.bin.tmp");

  // Removal: the segments given, the snapshots below the number and every temporary one; nothing else.
  for (const char* name : {"journal.log", "journal-1.log", "journal-2.log", "snapshot-0.bin", "snapshot-7.bin.tmp"}) {
    touch(dir.path / name);
  }
  thread.remove({(dir.path / "journal.log").string(), (dir.path / "journal-1.log").string()}, 1);
  thread.wait_idle();
  EXPECT_FALSE(fs::exists(dir.path / "journal.log"));
  EXPECT_FALSE(fs::exists(dir.path / "journal-1.log"));
  EXPECT_FALSE(fs::exists(dir.path / "snapshot-0.bin"));
  EXPECT_FALSE(fs::exists(dir.path / "snapshot-7.bin.tmp"));
  EXPECT_TRUE(fs::exists(dir.path / "journal-2.log"));
  EXPECT_TRUE(fs::exists(file));
  EXPECT_EQ(wakes.count, 2);  // removal wakes nobody

  // A segment created ahead: its header alone, durable; a failure (it exists already) leaves none prepared.
  thread.prepare(3);
  thread.wait_idle();
  EXPECT_EQ(thread.prepared(), 3u);
  EXPECT_EQ(fs::file_size(dir.path / "journal-3.log"), 16u);
  thread.prepare(3);
  thread.wait_idle();
  EXPECT_EQ(thread.prepared(), 0u);
  EXPECT_EQ(wakes.count, 2);
}

TEST(JournalSnapshotThread, DestructorFinishesTheSnapshotInHand) {
  Dir dir;
  {
    SnapshotThread thread(dir.path.string(), {});
    thread.write(3, sample_parts());
  }
  EXPECT_TRUE(fs::exists(dir.path / "snapshot-3.bin"));
  EXPECT_FALSE(fs::exists(dir.path / "snapshot-3.bin.tmp"));
}
