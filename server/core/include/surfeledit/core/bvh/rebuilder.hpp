// Rebuild aside (docs/algorithms.md §5 "rebuild on idle", thesis §8.3.3): a fresh tree is built on a
// background thread from a snapshot (copy) of the positions, while steps keep refitting and querying the
// current tree. The step thread adopts the new tree at a step boundary with take(), which never waits: it
// either hands over a completely built tree or nothing. The worker publishes the tree with a release store of
// the state after the build has finished, take() reads it with an acquire load, so no step can see a
// half-built tree.
//
// Since the snapshot is older than the step that adopts it, the adopter refits the new tree to the
// current positions (a bottom-up refit is cheap), and drops it if the model's rows were inserted or
// removed meanwhile (compare the `tag` given to start(), e.g. a topology version).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>

#include "surfeledit/core/bvh/bvh.hpp"

namespace surfeledit::bvh {

// What a session reports about its deformable tree.
enum class BvhStatus : std::uint8_t {
  Fresh = 0,       // built (or rebuilt) and not changed by a refit since
  Refit = 1,       // refit, insertions or removals since the last build: a rebuild would fit tighter
  Rebuilding = 2,  // a background rebuild is running
};
const char* to_string(BvhStatus status);

template <class Box>
class BvhRebuilder {
 public:
  BvhRebuilder() = default;
  BvhRebuilder(const BvhRebuilder&) = delete;
  BvhRebuilder& operator=(const BvhRebuilder&) = delete;
  ~BvhRebuilder() {
    if (worker_.joinable()) worker_.join();
  }

  // Starts a rebuild over `rows` from copies of `positions` and `radii`. Returns false (and does
  // nothing) while a previous rebuild is running or its result has not been taken. The copy is
  // made on the calling thread (about 1.5 MB for 60k surfels); the build runs on the worker.
  bool start(const Points& positions, const Values& radii, IndexList rows, const BvhParams& params,
             std::uint64_t tag = 0) {
    if (state_.load(std::memory_order_acquire) != kIdle) return false;
    if (worker_.joinable()) worker_.join();  // finished worker whose result was taken
    state_.store(kRunning, std::memory_order_relaxed);
    tag_ = tag;
    auto snapshot = std::make_shared<const Snapshot>(Snapshot{positions, radii, std::move(rows)});
    worker_ = std::thread([this, snapshot, params] {
      const auto t0 = std::chrono::steady_clock::now();
      auto tree = std::make_unique<Bvh<Box>>(snapshot->positions, snapshot->radii, snapshot->rows, params);
      result_ = std::move(tree);
      last_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      state_.store(kReady, std::memory_order_release);
    });
    return true;
  }

  // True from start() until the built tree is taken.
  bool running() const { return state_.load(std::memory_order_acquire) == kRunning; }
  // True when a finished tree waits to be taken.
  bool ready() const { return state_.load(std::memory_order_acquire) == kReady; }

  // Never blocks: the finished tree (and its tag) if one is ready, else nullptr.
  std::unique_ptr<Bvh<Box>> take(std::uint64_t* tag = nullptr) {
    if (state_.load(std::memory_order_acquire) != kReady) return nullptr;
    std::unique_ptr<Bvh<Box>> tree = std::move(result_);
    if (tag) *tag = tag_;
    state_.store(kIdle, std::memory_order_release);
    // The worker has stored kReady as its last action; it is joined lazily by the next start()
    // or the destructor, so take() does not wait for the thread to exit.
    return tree;
  }

  // Wall time of the last finished background build, ms (valid after take()).
  double last_build_ms() const { return last_ms_; }

 private:
  struct Snapshot {
    Points positions;
    Values radii;
    IndexList rows;
  };
  enum : int { kIdle = 0, kRunning = 1, kReady = 2 };

  std::atomic<int> state_{kIdle};
  std::thread worker_;
  std::unique_ptr<Bvh<Box>> result_;  // written by the worker before kReady, read by take() after
  double last_ms_ = 0.0;              // same hand-over as result_
  std::uint64_t tag_ = 0;             // written by start() before the worker exists
};

// Status of a deformable tree together with its rebuilder.
template <class Box>
BvhStatus status_of(const Bvh<Box>& tree, const BvhRebuilder<Box>& rebuilder) {
  if (rebuilder.running()) return BvhStatus::Rebuilding;
  return tree.refit_since_build() ? BvhStatus::Refit : BvhStatus::Fresh;
}

}  // namespace surfeledit::bvh
