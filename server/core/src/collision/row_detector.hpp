// The row detector: one kernel (kernel.hpp) driven over the deformable rows of a model. It does what
// every detector without clusters does alike -- reset, the row guards, the step's loop over the
// candidate rows (serial or OpenMP), insertions and removals, memory and the result -- once; the
// kernel says what one point's step is. A sweep policy runs the loop: ParallelSweep (independent
// points) or a kernel's own order-dependent sweep (Improved, improved_sweep.hpp).
#pragma once

#include <chrono>

#include "kernel.hpp"

namespace surfeledit::detail {

// Nearest-neighbour queries and points tested in one step.
struct Tally {
  Index tested = 0;   // points whose state was (re)evaluated (queries > 0)
  Index queries = 0;  // nearest-neighbour queries made
};

// The points of a step are independent: each row goes through update() (not_candidate() when the
// broad phase ruled it out), serially below 2048 rows or with one thread, else in OpenMP dynamic
// chunks of Kernel::kChunk rows. Results do not depend on the thread count.
struct ParallelSweep {
  void reset() {}

  template <typename Kernel>
  Tally run(const Kernel& kernel, const IndexList& rows, std::vector<typename Kernel::State>& states,
            const CollisionScene& scene, const Points& previous, const std::vector<std::uint8_t>* candidate,
            int threads) const {
    const Index n = static_cast<Index>(rows.size());
    Index tested = 0, queries = 0;
    auto one = [&](Index q) -> Index {
      const Index r = rows[q];
      const TestPoint pt{row3(scene.positions, r), scene.radii[r], row3(previous, r)};
      return candidate && !(*candidate)[r] ? kernel.not_candidate(states[r], pt) : kernel.update(states[r], pt);
    };
    if (threads == 1 || n < 2048) {
      for (Index q = 0; q < n; ++q) {
        const Index m = one(q);
        queries += m;
        tested += m > 0;
      }
    } else {
#pragma omp parallel for schedule(dynamic, Kernel::kChunk) num_threads(threads) reduction(+ : tested, queries)
      for (Index q = 0; q < n; ++q) {
        const Index m = one(q);
        queries += m;
        tested += m > 0;
      }
    }
    return {tested, queries};
  }
};

template <typename Kernel, typename Sweep = ParallelSweep>
class RowDetector final : public NarrowDetector {
 public:
  using State = typename Kernel::State;

  explicit RowDetector(const CollisionParams& params) : NarrowDetector(params), kernel_(params) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    const int threads = resolve_threads(params_.threads);
    Kernel kernel(params_);
    kernel.reset(scene, deformable, zero_rows, threads);
    std::vector<State> states(scene.regions.size());
    kernel.seed(scene, deformable, zero_rows, threads, states);
    kernel_ = std::move(kernel);
    deformable_ = std::move(deformable);
    states_ = std::move(states);
    rows_ = static_cast<Index>(states_.size());
    sweep_.reset();
    preprocess_ms_ = ms_since(start);
  }

  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* candidate) override {
    const auto start = std::chrono::steady_clock::now();
    require_scene_rows(scene, rows_, "detect");
    if (previous.rows() != rows_) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
    const Tally tally =
        sweep_.run(kernel_, deformable_, states_, scene, previous, candidate, resolve_threads(params_.threads));
    CollisionResult result;
    result.stats.tested = tally.tested;
    result.stats.queries = tally.queries;
    collect_result(
        result, deformable_, [&](std::size_t, Index r) { return states_[r].colliding(); },
        [&](std::size_t, Index r) { return states_[r].depth; }, preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
    const IndexList new_row = remap_rows(keep);
    kernel_.on_removed(keep, new_row);
    deformable_ = remap_list(deformable_, keep, new_row);
    compact(states_, keep);
    rows_ = static_cast<Index>(states_.size());
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    const Index added = static_cast<Index>(parents.size());
    require_scene_rows(scene, rows_ + added, "on_inserted");
    require_deformable_parents(scene, rows_, parents);
    split_states(kernel_, scene.positions, parents, states_);
    for (Index k = 0; k < added; ++k) deformable_.push_back(rows_ + k);
    kernel_.on_inserted(added);
    rows_ += added;
  }

  std::size_t memory_bytes() const override {
    return kernel_.memory_bytes() + deformable_.capacity() * sizeof(Index) + states_.capacity() * sizeof(State);
  }

 private:
  Kernel kernel_;
  Sweep sweep_;
  IndexList deformable_;      // rows with region != Zero, ascending
  Index rows_ = 0;            // rows of the model the state refers to
  std::vector<State> states_;  // #P (zero rows unused)
  double preprocess_ms_ = 0.0;
};

}  // namespace surfeledit::detail
