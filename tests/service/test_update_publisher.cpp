// UpdatePublisher: the bounded queue and thread that write update samples.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "service_test_support.hpp"
#include "surfeledit/service/update_publisher.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

namespace {

PreparedUpdate small_update(const std::string& session, std::uint64_t version, const std::string& cause,
                            std::size_t surfels = 10) {
  PreparedUpdate u;
  u.session = session;
  u.version = version;
  u.cause = cause;
  u.ids.assign(surfels, version);
  u.positions.assign(3 * surfels, 0.0);
  u.normals.assign(3 * surfels, 0.0);
  u.radii.assign(surfels, 0.0);
  return u;
}

// A writer that records what it wrote and can be held (to let the queue fill up).
struct RecordingWriter {
  std::mutex mutex;
  std::condition_variable cv;
  bool hold = false;
  std::size_t entered = 0;  // calls of the writer so far, held ones included
  std::vector<std::pair<std::string, std::uint64_t>> written;
  std::thread::id thread;

  UpdatePublisher::Writer writer() {
    return [this](const PreparedUpdate& u) {
      std::unique_lock<std::mutex> lock(mutex);
      ++entered;
      cv.notify_all();
      cv.wait(lock, [&] { return !hold; });
      thread = std::this_thread::get_id();
      if (u.cause == "boom") throw std::runtime_error("write failed");
      written.emplace_back(u.session, u.version);
    };
  }
  void set_hold(bool h) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      hold = h;
    }
    cv.notify_all();
  }
  // Whether the publisher's thread has called the writer `n` times within 10 s.
  bool wait_entered(std::size_t n) {
    std::unique_lock<std::mutex> lock(mutex);
    return cv.wait_for(lock, std::chrono::seconds(10), [&] { return entered >= n; });
  }
};

// Releases a held writer when the test leaves its scope, by a failed assertion too: declared after the publisher, it
// runs before the publisher's destructor, which joins the writer's thread.
struct ReleaseAtExit {
  RecordingWriter& w;
  ~ReleaseAtExit() { w.set_hold(false); }
};

}  // namespace

TEST(UpdatePublisher, WritesInOrderOnItsOwnThread) {
  RecordingWriter w;
  UpdatePublisher pub(w.writer(), 1 << 20);
  for (std::uint64_t v = 1; v <= 50; ++v) {
    PreparedUpdate u = small_update(v % 2 ? "a" : "b", v, "deform");
    ASSERT_TRUE(pub.push(u));
  }
  PreparedUpdate bad = small_update("a", 51, "boom");
  ASSERT_TRUE(pub.push(bad));
  pub.wait_idle();
  ASSERT_EQ(w.written.size(), 50u);
  for (std::uint64_t v = 1; v <= 50; ++v) EXPECT_EQ(w.written[v - 1].second, v);
  EXPECT_NE(w.thread, std::this_thread::get_id());
  const UpdatePublisher::Counters c = pub.shutdown();
  EXPECT_EQ(c.published, 50u);
  EXPECT_EQ(c.failed, 1u);
  EXPECT_EQ(c.dropped, 0u);
  PreparedUpdate late = small_update("a", 52, "deform");
  EXPECT_FALSE(pub.push(late));
}

TEST(UpdatePublisher, RefusesBeyondTheBoundAndHandsBackContiguousIncrementalUpdates) {
  RecordingWriter w;
  w.set_hold(true);
  const std::size_t one = small_update("s", 1, "deform").bytes();
  UpdatePublisher pub(w.writer(), 3 * one);
  const ReleaseAtExit release{w};
  PreparedUpdate first = small_update("s", 1, "deform");
  ASSERT_TRUE(pub.push(first));
  // The writer's thread holds the first update: from here on the queue changes only by this test's calls.
  ASSERT_TRUE(w.wait_entered(1));
  // Fill the queue until it refuses; the refused update is left intact.
  std::uint64_t v = 2;
  for (;; ++v) {
    PreparedUpdate u = small_update("s", v, "deform");
    if (!pub.push(u)) {
      EXPECT_EQ(u.ids.size(), 10u);
      break;
    }
    ASSERT_LT(v, 10u) << "the bound was never reached";
  }
  EXPECT_LE(pub.queued_bytes(), 3 * one);
  // Not contiguous with the next version: nothing is handed back.
  EXPECT_TRUE(pub.take_pending("s", v + 1, {"deform"}).empty());
  // A cause not in the list: nothing.
  EXPECT_TRUE(pub.take_pending("s", v, {"remove"}).empty());
  const std::size_t queued = pub.queued_updates();
  std::vector<PreparedUpdate> back = pub.take_pending("s", v, {"deform"});
  ASSERT_EQ(back.size(), queued);
  EXPECT_EQ(back.back().version, v - 1);
  EXPECT_EQ(pub.queued_bytes(), 0u);
  // push_anyway ignores the bound.
  for (std::uint64_t k = 0; k < 5; ++k) EXPECT_TRUE(pub.push_anyway(small_update("t", k + 1, "deform")));
  EXPECT_GT(pub.queued_bytes(), 3 * one);
  w.set_hold(false);
  pub.wait_idle();
  EXPECT_EQ(pub.counters().taken_back, queued);
}

TEST(UpdatePublisher, ShutdownDrainsWithinTheDeadlineAndDropsTheRest) {
  {
    RecordingWriter w;
    UpdatePublisher pub(w.writer(), 1 << 20);
    for (std::uint64_t v = 1; v <= 20; ++v) ASSERT_TRUE(pub.push_anyway(small_update("s", v, "deform")));
    const UpdatePublisher::Counters c = pub.shutdown(std::chrono::milliseconds(5000));
    EXPECT_EQ(c.published, 20u);
    EXPECT_EQ(c.dropped, 0u);
    EXPECT_EQ(w.written.size(), 20u);
  }
  {
    RecordingWriter w;
    w.set_hold(true);
    UpdatePublisher pub(w.writer(), 1 << 20);
    const ReleaseAtExit release_at_exit{w};
    for (std::uint64_t v = 1; v <= 5; ++v) ASSERT_TRUE(pub.push_anyway(small_update("s", v, "deform")));
    std::thread release([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      w.set_hold(false);
    });
    const UpdatePublisher::Counters c = pub.shutdown(std::chrono::milliseconds(0));
    release.join();
    // The update being written when the deadline passed is finished; the others are dropped.
    EXPECT_EQ(c.published + c.dropped, 5u);
    EXPECT_GE(c.dropped, 4u);
  }
}
