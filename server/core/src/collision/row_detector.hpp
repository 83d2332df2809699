// The row detector: one kernel (kernel.hpp) driven over the deformable rows of a model. It does what
// every detector without clusters does alike -- reset, the row guards, the step's loop over the
// candidate rows (serial or OpenMP), insertions and removals, memory and the result -- once; the
// kernel says what one point's step is. A sweep policy runs the loop: ParallelSweep (independent
// points) or a kernel's own order-dependent sweep (Improved, improved_sweep.hpp).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>

#include "kernel_rows.hpp"
#include "parallel_sweep.hpp"
#include "row_journal.hpp"
#include "row_states_snapshot.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit::detail {

// A kernel's reset_rows() when it has one (Robust), none otherwise.
template <typename K>
auto kernel_reset_rows(const K& kernel, int) -> decltype(kernel.reset_rows()) {
  return kernel.reset_rows();
}
template <typename K>
CollisionDetector::ResetRows kernel_reset_rows(const K&, long) {
  return {};
}

// Whether a kernel has open_boundary() (Robust).
template <typename K, typename = void>
struct HasOpenBoundary : std::false_type {};
template <typename K>
struct HasOpenBoundary<K, std::void_t<decltype(std::declval<const K&>().open_boundary())>> : std::true_type {};

template <typename Kernel, typename Sweep = ParallelSweep>
class RowDetector final : public NarrowDetector {
 public:
  explicit RowDetector(const CollisionParams& params)
      : NarrowDetector(params), rows_(params), sweep_(params), journal_sweep_(params) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    const int threads = resolve_threads(params_.threads);
    rows_ = KernelRows<Kernel>::build_seeded(params_, scene, threads);
    sweep_.reset();
    size_sleep();
    journal_.on = false;
    preprocess_ms_ = ms_since(start);
  }

  std::vector<ZeroBall> open_boundary(const CollisionScene& scene) override {
    if constexpr (HasOpenBoundary<Kernel>::value) {
      rows_.kernel.bind(scene);  // builds the inside model a removal of zero rows left pending
      return rows_.kernel.open_boundary();
    } else {
      (void)scene;
      return {};
    }
  }

  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* candidate) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    checked_displacement_bound(scene);  // the sweep's sleeping blocks read it
    rows_.kernel.bind(scene);
    hit_.resize(rows_.deformable.size());
    const Tally tally = sweep(rows_.deformable, scene, previous, candidate);
    CollisionResult result;
    result.stats.tested = tally.tested;
    result.stats.queries = tally.queries;
    result.stats.asleep = tally.asleep;
    collect_hits(
        result, rows_.deformable, hit_,
        [&](std::size_t q, Index r) { return rows_.kernel.depth(rows_.states.stored_data()[q], row3(scene.positions, r)); },
        preprocess_ms_, start);
    return result;
  }

  // Rows renumbered or added: the journal (by row) ends.
  void on_removed(const std::vector<bool>& keep) override {
    journal_.on = false;
    rows_.on_removed(keep);
    size_sleep();
  }
  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    journal_.on = false;
    rows_.on_inserted(scene, parents);
    size_sleep();
  }
  // Rigid rows moved (another tool's op): the kernel updates its references and the states that
  // depended on them. Rows that are not Zero, or a scene of another row count: false, nothing changed.
  bool on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& before) override {
    const Index n = rows_.rows();
    if (scene.positions.rows() != n || static_cast<Index>(scene.regions.size()) != n) return false;
    for (Index r : rows)
      if (r < 0 || r >= n || scene.regions[static_cast<std::size_t>(r)] != Region::Zero) return false;
    const auto size = static_cast<Eigen::Index>(rows.size());
    if (before.positions.rows() != size || before.normals.rows() != size || before.radii.size() != size) return false;
    journal_.on = false;
    sleep_.clear();
    return rows_.kernel.on_rigid_moved(scene, rows, before, rows_.deformable, rows_.states,
                                       resolve_threads(params_.threads));
  }
  std::size_t memory_bytes() const override {
    return rows_.memory_bytes() + hit_.capacity() + journal_.saved.capacity() + sleep_.memory_bytes();
  }
  ResetRows reset_rows() const override { return kernel_reset_rows(rows_.kernel, 0); }

  // A step changes only the deformable rows' states and the sweep's tallies (hit_ is scratch); the
  // kernel's references change at reset, removal and insertion only (clone() copies them; their
  // trees are immutable and shared).
  struct Image final : DetectorImage {
    IndexList rows;                              // the rows saved; empty = rows_.deformable unless `listed`
    bool listed = false;                         // `rows` are exactly the rows saved (even when empty)
    std::vector<typename Kernel::State> states;  // one per saved row, in that order
    Sweep sweep;
    std::size_t bytes() const override { return states.capacity() * sizeof(typename Kernel::State) + sizeof(*this); }
  };
  std::shared_ptr<const DetectorImage> save_image(const IndexList* rows) const override {
    auto image = std::make_shared<Image>();
    if (rows) image->rows = *rows;
    image->listed = rows != nullptr;
    const IndexList& saved = rows ? *rows : rows_.deformable;
    image->states.reserve(saved.size());
    for (Index r : saved) image->states.push_back(rows_.states[r]);
    image->sweep = sweep_;
    return image;
  }
  void restore_image(const DetectorImage& image) override {
    const auto* mine = dynamic_cast<const Image*>(&image);
    const IndexList* saved = mine && (mine->listed || !mine->rows.empty()) ? &mine->rows : &rows_.deformable;
    if (!mine || mine->states.size() != saved->size() || (!saved->empty() && saved->back() >= rows_.rows())) {
      throw Error(ErrorCode::Internal, "history", "detector image does not fit this detector");
    }
    for (std::size_t q = 0; q < mine->states.size(); ++q) rows_.states[(*saved)[q]] = mine->states[q];
    sweep_ = mine->sweep;
    sleep_.clear();
  }
  CollisionResult detect_only(const CollisionScene& scene, const Points& previous,
                              const std::vector<std::uint8_t>& candidate) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    rows_.kernel.bind(scene);
    IndexList rows;
    for (Index r : rows_.deformable)
      if (candidate[static_cast<std::size_t>(r)]) rows.push_back(r);
    sleep_.clear();  // the budgets are of the whole list's last sweep
    hit_.resize(rows.size());
    const Tally tally = sweep(rows, scene, previous, nullptr);
    CollisionResult result;
    result.stats.tested = tally.tested;
    result.stats.queries = tally.queries;
    collect_hits(
        result, rows, hit_, [&](std::size_t, Index r) { return rows_.kernel.depth(rows_.states[r], row3(scene.positions, r)); },
        preprocess_ms_, start);
    return result;
  }
  std::unique_ptr<CollisionDetector> clone() const override {
    auto out = std::make_unique<RowDetector>(params_);
    out->rows_ = rows_;
    out->sweep_ = sweep_;
    out->size_sleep();
    out->preprocess_ms_ = preprocess_ms_;
    return out;
  }

  // The journal (independent points only: an order-dependent sweep saves images before the step). When
  // most rows changed at the last journal (e.g. a step that tested most rows), copying
  // them twice costs more than one image before the step: the next steps only note the tested rows.
  bool start_journal() override {
    if constexpr (!std::is_same_v<Sweep, ParallelSweep>) {
      return false;
    } else {
      const bool save = dense_skip_ == 0;
      if (dense_skip_ > 0) --dense_skip_;
      journal_.start(rows_.states.size(), save);
      journal_sweep_ = sweep_;
      return save;
    }
  }
  std::shared_ptr<const DetectorImage> journal_image() const override {
    if (!journal_.on || !journal_.save) return nullptr;
    auto image = std::make_shared<Image>();
    const std::size_t n = journal_.count();
    image->rows.reserve(n);
    image->states.reserve(n);
    journal_.for_each_by_row([&](const auto& e) {
      image->rows.push_back(e.row);
      image->states.push_back(e.state);
    });
    image->sweep = journal_sweep_;
    image->listed = true;
    return image;
  }
  void restore_journal() override {
    if (!journal_.on || !journal_.save) throw Error(ErrorCode::Internal, "history", "no journal to restore");
    journal_.for_each([&](const auto& e) { rows_.states[e.row] = e.state; });
    sweep_ = journal_sweep_;
    sleep_.clear();
  }
  bool journal_tested(std::vector<std::uint8_t>& flags) const override {
    if (!journal_.on || flags.size() != journal_.tested.size()) return false;
    for (std::size_t r = 0; r < flags.size(); ++r) flags[r] |= journal_.tested[r];
    return true;
  }
  void stop_journal() override {
    if (journal_.on && journal_.save) dense_skip_ = 2 * journal_.count() > rows_.deformable.size() ? kDenseSkip : 0;
    journal_.on = false;
  }

  // Snapshots: the kernel's references, the deformable rows, every state, and what decides the next steps'
  // history images (the dense-journal countdown) and the history's byte counts (capacities). Not for an
  // order-dependent sweep (Improved) nor a kernel with an inside model.
  bool snapshottable() const override {
    if constexpr (!std::is_same_v<Sweep, ParallelSweep>) {
      return false;
    } else {
      return rows_.kernel.snapshottable();
    }
  }
  void save_state(SnapshotWriter& out) const override {
    if (!snapshottable()) throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
    put_states(out, rows_.states);
    out.vec(rows_.deformable);
    rows_.kernel.save(out);
    out.f64(preprocess_ms_);
    out.u32(static_cast<std::uint32_t>(dense_skip_));
    out.u64(hit_.capacity());
    out.u64(journal_.saved.capacity());
  }
  void load_state(SnapshotReader& in) override {
    if (!snapshottable()) throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
    KernelRows<Kernel> rows(params_);
    rows.states = get_row_states<typename Kernel::State>(in);
    rows.deformable = in.vec<Index>("deformable rows");
    check_rows(in, rows.deformable, rows.rows(), "deformable rows");
    if (rows.states.dense().size() != rows.deformable.size()) in.fail("detector states", "not one per deformable row");
    const std::vector<Index> slots = rows.states.slots();
    for (Index r : rows.deformable) {
      if (slots[static_cast<std::size_t>(r)] < 0) in.fail("detector states", "a deformable row without one");
    }
    rows.kernel.load(in, rows.rows());
    const double preprocess = in.f64("preprocess_ms");
    const std::uint32_t skip = in.u32("dense_skip");
    if (skip > static_cast<std::uint32_t>(kDenseSkip)) in.fail("dense_skip", "out of range");
    const std::size_t hit_cap = in.capacity("hit capacity", 0, 1);
    const std::size_t saved_cap = in.capacity("journal capacity", 0, 1);
    rows_ = std::move(rows);
    sweep_.reset();
    size_sleep();
    preprocess_ms_ = preprocess;
    dense_skip_ = static_cast<int>(skip);
    journal_ = Journal<typename Kernel::State>();
    journal_.saved.reserve(saved_cap);
    hit_ = std::vector<std::uint8_t>();
    hit_.reserve(hit_cap);
  }
  void save_image_state(SnapshotWriter& out, const DetectorImage& image) const override {
    const auto* mine = dynamic_cast<const Image*>(&image);
    if (!mine) throw Error(ErrorCode::Internal, "snapshot", "detector image of another detector type");
    out.vec(mine->rows);
    out.boolean(mine->listed);
    put_states(out, mine->states);
  }
  std::shared_ptr<const DetectorImage> load_image_state(SnapshotReader& in) const override {
    auto image = std::make_shared<Image>();
    image->rows = in.vec<Index>("detector image rows");
    check_rows(in, image->rows, std::numeric_limits<Index>::max(), "detector image rows");
    image->listed = in.boolean("detector image listed");
    image->states = get_states<typename Kernel::State>(in);
    if (!image->rows.empty() && image->rows.size() != image->states.size()) in.fail("detector image", "rows and states differ");
    return image;
  }

 private:
  Tally sweep(const IndexList& rows, const CollisionScene& scene, const Points& previous,
              const std::vector<std::uint8_t>* candidate) {
    const int threads = resolve_threads(params_.threads);
    if constexpr (std::is_same_v<Sweep, ParallelSweep>) {
      const bool by_slot = &rows == &rows_.deformable;
      const bool journal = journal_.on && journal_.tested.size() == rows_.states.size();
      return sweep_.run(rows_.kernel, rows, rows_.states, scene, previous, candidate, threads, hit_, by_slot,
                        journal ? &journal_ : nullptr, by_slot ? &sleep_ : nullptr);
    } else {
      return sweep_.run(rows_.kernel, rows, rows_.states, scene, previous, candidate, threads, hit_);
    }
  }

  KernelRows<Kernel> rows_;
  Sweep sweep_;
  // The sweep's sleeping blocks (parallel_sweep.hpp): not in images nor clones nor snapshots, cleared whenever the
  // states or rows change but by a sweep of the whole list (the next step then sweeps every block).
  SleepingBlocks sleep_;
  // sleep_ with one budget of 0 per block of the deformable rows (none when the sweep cannot use them), at exactly
  // that capacity (memory_bytes() is the same after a snapshot's load).
  void size_sleep() {
    if constexpr (std::is_same_v<Sweep, ParallelSweep> && kQuiet<Kernel>) sleep_.size_for(rows_.deformable.size());
  }
  std::vector<std::uint8_t> hit_;  // #deformable: colliding after the last step (filled by the sweep)
  double preprocess_ms_ = 0.0;  // the last reset
  Journal<typename Kernel::State> journal_;  // states before the first change since start_journal()
  Sweep journal_sweep_;                     // the sweep's tallies at start_journal()
  static constexpr int kDenseSkip = 7;      // steps without saved states after a dense journal
  int dense_skip_ = 0;                      // steps left before the journal saves states again
};

}  // namespace surfeledit::detail
