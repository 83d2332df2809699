// share_chunks (server/core/src/share_chunks.hpp): every chunk once, whatever the threads; the lowest throwing
// chunk's exception; a caller that finishes without any helper when none can run; helpers that help.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "share_chunks.hpp"

namespace surfeledit::detail {
namespace {

// How often each chunk of [0, chunks) ran.
std::vector<int> runs_of(int threads, Index chunks) {
  std::unique_ptr<std::atomic<int>[]> runs(new std::atomic<int>[static_cast<std::size_t>(chunks) + 1]());
  share_chunks(threads, chunks, [&](Index c) { runs[static_cast<std::size_t>(c)].fetch_add(1); });
  std::vector<int> out;
  for (Index c = 0; c < chunks; ++c) out.push_back(runs[static_cast<std::size_t>(c)].load());
  return out;
}

TEST(ShareChunks, EveryChunkRunsOnceWhateverTheThreads) {
  for (int threads : {1, 2, 3, 8}) {
    for (Index chunks : {0, 1, 2, 7, 1000}) {
      EXPECT_EQ(runs_of(threads, chunks), std::vector<int>(static_cast<std::size_t>(chunks), 1))
          << threads << " threads, " << chunks << " chunks";
    }
  }
}

TEST(ShareChunks, TheLowestThrowingChunksExceptionIsRethrownAfterTheOthersRan) {
  for (int threads : {1, 2, 4}) {
    std::atomic<int> ran{0};
    try {
      share_chunks(threads, 200, [&](Index c) {
        ran.fetch_add(1);
        if (c == 150 || c == 37 || c == 90) throw std::runtime_error("chunk " + std::to_string(c));
      });
      ADD_FAILURE() << "nothing thrown at " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "chunk 37") << threads << " threads";
    }
    EXPECT_EQ(ran.load(), 200) << threads << " threads";
  }
}

// Every helper of the pool is held busy (as when every one is descheduled): a loop asking for helpers is run by
// its caller alone, which returns without waiting for them. (An OpenMP region waits for every thread of its team,
// so a helper that cannot run would hold it until the helpers are released, 20 s here.)
TEST(ShareChunks, TheCallerFinishesAloneWhileEveryHelperIsBusy) {
  const int helpers = helper_threads();
  std::atomic<int> held{0};
  std::atomic<bool> release{false};
  std::atomic<int> ran{0}, elsewhere{0};
  double inner_s = -1.0;
  const std::thread::id caller = std::this_thread::get_id();
  // The outer loop: the caller's chunk waits until every helper holds one of the others, runs the inner loop,
  // then releases them.
  share_chunks(helpers + 1, helpers + 1, [&](Index) {
    if (std::this_thread::get_id() != caller) {
      held.fetch_add(1);
      for (int i = 0; i < 20000 && !release; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      return;
    }
    for (int i = 0; i < 10000 && held.load() < helpers; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto t0 = std::chrono::steady_clock::now();
    share_chunks(4, 64, [&](Index) {
      ran.fetch_add(1);
      if (std::this_thread::get_id() != caller) elsewhere.fetch_add(1);
    });
    inner_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    release = true;
  });
  ASSERT_EQ(held.load(), helpers) << "the helpers did not all take a chunk of the outer loop";
  EXPECT_EQ(ran.load(), 64);
  EXPECT_EQ(elsewhere.load(), 0);
  EXPECT_LT(inner_s, 5.0);
}

// With helpers that can run, a loop long enough to wake one is shared: some chunk ran on another thread.
TEST(ShareChunks, HelpersTakeChunksWhenTheyCanRun) {
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one hardware thread: no helper runs beside the caller";
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<int> elsewhere{0};
  std::atomic<bool> helped{false};
  share_chunks(2, 1000, [&](Index c) {
    if (std::this_thread::get_id() != caller) {
      elsewhere.fetch_add(1);
      helped = true;
    }
    // The caller's first chunk waits (up to 10 s) until a helper took one, so that the test does not depend on
    // how soon the helper wakes.
    if (c == 0) {
      for (int i = 0; i < 10000 && !helped; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  EXPECT_GT(elsewhere.load(), 0);
}

// Several callers at once (sessions stepping on their own threads) share the one pool: each loop still runs every
// one of its chunks once, and none waits on another's.
TEST(ShareChunks, CallersOnSeveralThreadsAtOnceEachRunTheirChunksOnce) {
  constexpr int kCallers = 4, kLoops = 100;
  constexpr Index kChunks = 300;
  std::vector<int> wrong(kCallers, 0);
  std::vector<std::thread> callers;
  for (int t = 0; t < kCallers; ++t) {
    callers.emplace_back([&, t] {
      for (int loop = 0; loop < kLoops; ++loop) {
        if (runs_of(2 + t % 2, kChunks) != std::vector<int>(static_cast<std::size_t>(kChunks), 1)) ++wrong[t];
      }
    });
  }
  for (std::thread& c : callers) c.join();
  EXPECT_EQ(wrong, std::vector<int>(kCallers, 0));
}

}  // namespace
}  // namespace surfeledit::detail
