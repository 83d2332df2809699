// share_chunks (share_chunks.hpp): a shared range of chunks; the helpers are tasks posted to one process-wide
// Boost.Asio thread pool. Asio is header-only, so ThreadSanitizer sees its hand-over of a task (oneTBB, tried first,
// is a compiled library that Debian does not instrument: TSan reported every hand-over as a race).
#include "share_chunks.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/thread_pool.hpp>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>

#include "surfeledit/core/util.hpp"

namespace surfeledit::detail {
namespace {

// The helpers' threads, made on first use.
boost::asio::thread_pool& helper_pool() {
  static boost::asio::thread_pool pool(static_cast<std::size_t>(helper_threads()));
  return pool;
}

// One loop. A helper joins only while the loop is open; the caller closes it once its own claims ran out and waits
// for the helpers that joined. A helper task that runs later finds it closed and touches nothing of the caller's
// (the job outlives the call through the tasks' shared pointers).
struct Job {
  std::atomic<std::uint64_t> ends{0};  // the first unclaimed chunk (high 32 bits), one past the last (low 32 bits)
  const std::function<void(Index)>* chunk = nullptr;
  std::mutex mutex;
  std::condition_variable idle;
  bool open = true;
  int joined = 0;  // helpers inside take()
  std::exception_ptr error;
  Index error_chunk = 0;

  // Claims chunks one at a time until none is left: the caller from the front, helpers from the back, so that
  // the loops of one step (deformation, sweep, copies over the same rows in the same order) give each thread
  // mostly the rows it had in the loop before, still in its cache.
  void take(bool front) {
    for (;;) {
      std::uint64_t e = ends.load(std::memory_order_relaxed);
      Index c;
      do {
        const std::uint64_t lo = e >> 32, hi = e & 0xffffffffu;
        if (lo >= hi) return;
        c = static_cast<Index>(front ? lo : hi - 1);
      } while (!ends.compare_exchange_weak(e, front ? e + (std::uint64_t{1} << 32) : e - 1, std::memory_order_relaxed));
      try {
        (*chunk)(c);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (c < error_chunk) {
          error_chunk = c;
          error = std::current_exception();
        }
      }
    }
  }

  void help() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!open) return;
      ++joined;
    }
    take(false);
    std::lock_guard<std::mutex> lock(mutex);
    if (--joined == 0) idle.notify_one();
  }
};

}  // namespace

int helper_threads() { return std::max(1, hardware_threads() - 1); }

void share_chunks(int threads, Index chunks, const std::function<void(Index)>& chunk) {
  if (chunks <= 0) return;
  auto job = std::make_shared<Job>();
  job->ends = static_cast<std::uint64_t>(chunks);
  job->chunk = &chunk;
  job->error_chunk = chunks;
  const Index helpers = std::min<Index>(threads, chunks) - 1;
  for (Index h = 0; h < helpers; ++h) boost::asio::post(helper_pool(), [job] { job->help(); });
  job->take(true);
  std::unique_lock<std::mutex> lock(job->mutex);
  job->open = false;
  job->idle.wait(lock, [&] { return job->joined == 0; });
  if (job->error) std::rethrow_exception(job->error);
}

}  // namespace surfeledit::detail
