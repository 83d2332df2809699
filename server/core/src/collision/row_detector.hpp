// The row detector: one kernel (kernel.hpp) driven over the deformable rows of a model. It does what
// every detector without clusters does alike -- reset, the row guards, the step's loop over the
// candidate rows (serial or OpenMP), insertions and removals, memory and the result -- once; the
// kernel says what one point's step is. A sweep policy runs the loop: ParallelSweep (independent
// points) or a kernel's own order-dependent sweep (Improved, improved_sweep.hpp).
#pragma once

#include <chrono>

#include "kernel_rows.hpp"

namespace surfeledit::detail {

// Nearest-neighbour queries and points tested in one step.
struct Tally {
  Index tested = 0;   // points whose state was (re)evaluated (queries > 0)
  Index queries = 0;  // nearest-neighbour queries made
};

// The points of a step are independent: each row goes through update() (not_candidate() when the
// broad phase ruled it out), serially below 2048 rows or with one thread, else in OpenMP dynamic
// chunks of Kernel::kChunk rows. Results do not depend on the thread count.
// Every sweep also fills hit[q] (#rows): 1 when rows[q] collides after the step.
struct ParallelSweep {
  void reset() {}

  template <typename Kernel>
  Tally run(const Kernel& kernel, const IndexList& rows, std::vector<typename Kernel::State>& states,
            const CollisionScene& scene, const Points& previous, const std::vector<std::uint8_t>* candidate,
            int threads, std::vector<std::uint8_t>& hit) const {
    const Index n = static_cast<Index>(rows.size());
    Index tested = 0, queries = 0;
    auto one = [&](Index q) -> Index {
      const Index r = rows[q];
      const TestPoint pt = row_point(scene, previous, r);
      auto& s = states[r];
      const Index made = candidate && !(*candidate)[r] ? kernel.not_candidate(s, pt) : kernel.update(s, pt);
      hit[q] = s.colliding();  // read while the state is in cache
      return made;
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
  explicit RowDetector(const CollisionParams& params) : NarrowDetector(params), rows_(params) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    const int threads = resolve_threads(params_.threads);
    IndexList zero_rows;
    KernelRows<Kernel> rows = KernelRows<Kernel>::build(params_, scene, threads, zero_rows);
    rows.kernel.seed(scene, rows.deformable, zero_rows, threads, rows.states);
    rows_ = std::move(rows);
    sweep_.reset();
    preprocess_ms_ = ms_since(start);
  }

  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* candidate) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    hit_.resize(rows_.deformable.size());
    const Tally tally = sweep_.run(rows_.kernel, rows_.deformable, rows_.states, scene, previous, candidate,
                                   resolve_threads(params_.threads), hit_);
    CollisionResult result;
    result.stats.tested = tally.tested;
    result.stats.queries = tally.queries;
    collect_result(
        result, rows_.deformable, [&](std::size_t q, Index) { return hit_[q] != 0; },
        [&](std::size_t, Index r) { return rows_.kernel.depth(rows_.states[r], row3(scene.positions, r)); },
        preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override { rows_.on_removed(keep); }
  void on_inserted(const CollisionScene& scene, const IndexList& parents) override { rows_.on_inserted(scene, parents); }
  std::size_t memory_bytes() const override { return rows_.memory_bytes() + hit_.capacity(); }

  // A step changes only the deformable rows' states and the sweep's tallies (hit_ is scratch); the
  // kernel's references change at reset, removal and insertion only (clone() copies them; their
  // trees are immutable and shared).
  struct Image final : DetectorImage {
    IndexList rows;                              // the rows saved; empty = rows_.deformable
    std::vector<typename Kernel::State> states;  // one per saved row, in that order
    Sweep sweep;
    std::size_t bytes() const override { return states.capacity() * sizeof(typename Kernel::State) + sizeof(*this); }
  };
  std::shared_ptr<const DetectorImage> save_image(const IndexList* rows) const override {
    auto image = std::make_shared<Image>();
    if (rows) image->rows = *rows;
    const IndexList& saved = rows ? *rows : rows_.deformable;
    image->states.reserve(saved.size());
    for (Index r : saved) image->states.push_back(rows_.states[r]);
    image->sweep = sweep_;
    return image;
  }
  void restore_image(const DetectorImage& image) override {
    const auto* mine = dynamic_cast<const Image*>(&image);
    const IndexList* saved = mine && !mine->rows.empty() ? &mine->rows : &rows_.deformable;
    if (!mine || mine->states.size() != saved->size() || (!saved->empty() && saved->back() >= rows_.rows())) {
      throw Error(ErrorCode::Internal, "history", "detector image does not fit this detector");
    }
    for (std::size_t q = 0; q < mine->states.size(); ++q) rows_.states[(*saved)[q]] = mine->states[q];
    sweep_ = mine->sweep;
  }
  CollisionResult detect_only(const CollisionScene& scene, const Points& previous,
                              const std::vector<std::uint8_t>& candidate) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    IndexList rows;
    for (Index r : rows_.deformable)
      if (candidate[static_cast<std::size_t>(r)]) rows.push_back(r);
    hit_.resize(rows.size());
    const Tally tally = sweep_.run(rows_.kernel, rows, rows_.states, scene, previous, nullptr,
                                   resolve_threads(params_.threads), hit_);
    CollisionResult result;
    result.stats.tested = tally.tested;
    result.stats.queries = tally.queries;
    collect_result(
        result, rows, [&](std::size_t q, Index) { return hit_[q] != 0; },
        [&](std::size_t, Index r) { return rows_.kernel.depth(rows_.states[r], row3(scene.positions, r)); },
        preprocess_ms_, start);
    return result;
  }
  std::unique_ptr<CollisionDetector> clone() const override { return std::make_unique<RowDetector>(*this); }

 private:
  KernelRows<Kernel> rows_;
  Sweep sweep_;
  std::vector<std::uint8_t> hit_;  // #deformable: colliding after the last step (filled by the sweep)
  double preprocess_ms_ = 0.0;  // the last reset
};

}  // namespace surfeledit::detail
