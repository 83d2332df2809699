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

#include "kernel_rows.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit::detail {

// Nearest-neighbour queries and points tested in one step.
struct Tally {
  Index tested = 0;   // points whose state was (re)evaluated (queries > 0)
  Index queries = 0;  // nearest-neighbour queries made
};

// Undo support (history.hpp): the state every row had when the journal started, for the rows a sweep
// changed since (first change wins). Each sweep appends (row, state before) to one part per chunk of its
// rows (Kernel::kChunk rows, one thread each; one part when it runs serially), so the saved states are
// written and read back in sequence, and a single sweep's parts in order are in ascending row order
// whatever the threads (its rows are ascending). Only from a journal's second sweep on are rows flagged
// as saved (a row appears once in a sweep).
template <typename State>
struct Journal {
  struct Saved {
    Index row;    // model row
    State state;  // its state when the journal started
  };
  bool on = false;
  bool save = false;                       // keep states (else only `tested`)
  std::vector<std::uint8_t> tested;        // #P: 1 = the kernel made a query for the row since the start
  // Parts [0, used): the sweeps' chunks in order. Step scratch (buffers reused), not in memory_bytes(), as
  // the #P-state buffer they replace was not: about 56 bytes per changed row (the 1M drag: ~3 MB).
  std::vector<std::vector<Saved>> parts;
  std::size_t used = 0;                    // parts of this journal
  int sweeps = 0;                          // sweeps since the start
  std::vector<std::uint8_t> saved;         // #P, from the second sweep on: 1 = the row is in a part

  void start(std::size_t rows, bool save_states) {
    on = true;
    save = save_states;
    tested.assign(rows, 0);
    used = 0;
    sweeps = 0;
  }
  // A sweep in `chunks` parts begins; returns its first part.
  std::size_t begin_sweep(std::size_t chunks) {
    if (!save) return 0;
    if (++sweeps == 2) {  // rows may repeat from now on: flag the rows saved so far
      saved.assign(tested.size(), 0);
      for_each([&](const Saved& e) { saved[static_cast<std::size_t>(e.row)] = 1; });
    }
    const std::size_t base = used;
    used += chunks;
    if (parts.size() < used) parts.resize(used);
    for (std::size_t k = base; k < used; ++k) parts[k].clear();
    return base;
  }
  // Called with a row's state before and after one update that made `queries` queries, in part `part` of
  // the sweep; different bytes: the row changed.
  void note(Index r, const State& before, const State& after, Index queries, std::size_t part) {
    if (queries > 0) tested[static_cast<std::size_t>(r)] = 1;
    if (!save || std::memcmp(&before, &after, sizeof(State)) == 0) return;
    if (sweeps > 1) {
      if (saved[static_cast<std::size_t>(r)]) return;
      saved[static_cast<std::size_t>(r)] = 1;
    }
    parts[part].push_back({r, before});
  }
  std::size_t count() const {
    std::size_t n = 0;
    for (std::size_t k = 0; k < used; ++k) n += parts[k].size();
    return n;
  }
  // f(Saved) for every saved row, in the parts' order.
  template <typename F>
  void for_each(F f) const {
    for (std::size_t k = 0; k < used; ++k)
      for (const Saved& e : parts[k]) f(e);
  }
  // f(Saved) for every saved row, in ascending row order.
  template <typename F>
  void for_each_by_row(F f) const {
    if (sweeps <= 1) return for_each(f);
    std::vector<const Saved*> all;
    all.reserve(count());
    for_each([&](const Saved& e) { all.push_back(&e); });
    std::sort(all.begin(), all.end(), [](const Saved* a, const Saved* b) { return a->row < b->row; });
    for (const Saved* e : all) f(*e);
  }
};

// The points of a step are independent: each row goes through update() (not_candidate() when the
// broad phase ruled it out), in OpenMP dynamic chunks of Kernel::kChunk rows when the step's work is
// large enough to pay for waking the other threads, else serially. Results do not depend on either.
// Every sweep also fills hit[q] (#rows): 1 when rows[q] collides after the step.
//
// The work is not known before the step, so the previous step's stands for it (steps of one drag are
// alike): `rows` x kRowNs + its nearest-neighbour queries x kQueryNs, from one-thread profiles of the
// Robust step (RESULTS §23: ~5 ns a row that stays in its sphere, ~0.37 us a query). Below kParallelNs a
// step runs on one thread: a parallel region costs little on an idle machine, but on a busy one a worker
// that is not running waits for the scheduler's next tick (steps of 0.3 ms took 4, 8 or 16 ms), which
// only work of a millisecond or more can hide (RESULTS §35). The threshold is the setting parallel_min_ms.
struct ParallelSweep {
  static constexpr double kRowNs = 5.0;      // per row of the sweep (estimate, one thread)
  static constexpr double kQueryNs = 400.0;  // per nearest-neighbour query (estimate, one thread)
  double min_ns = 1.0e6;                     // the least estimated work run on several threads (parallel_min_ms)
  Index last_queries = 0;                    // queries of the previous sweep (0 after a reset)

  ParallelSweep() = default;
  explicit ParallelSweep(const CollisionParams& params) : min_ns(params.parallel_min_ms * 1.0e6) {}
  void reset() { last_queries = 0; }
  // Whether a sweep over `n` rows runs on several threads, from the previous sweep's queries.
  bool parallel(Index n, int threads) const {
    return threads > 1 && static_cast<double>(n) * kRowNs + static_cast<double>(last_queries) * kQueryNs >= min_ns;
  }

  // `journal` (may be null): notes each row's state before its update. `by_slot`: `rows` are exactly the
  // rows with a state, in order (the deformable list), so rows[q]'s state is the q-th stored one and the
  // sweep walks the states in storage order without the row -> slot map (RESULTS §39).
  template <typename Kernel>
  Tally run(const Kernel& kernel, const IndexList& rows, RowStates<typename Kernel::State>& states,
            const CollisionScene& scene, const Points& previous, const std::vector<std::uint8_t>* candidate,
            int threads, std::vector<std::uint8_t>& hit, bool by_slot,
            Journal<typename Kernel::State>* journal = nullptr) {
    const Index n = static_cast<Index>(rows.size());
    if (by_slot && states.stored() != rows.size()) throw Error(ErrorCode::Internal, "rows", "not one per state");
    // One loop per combination of the three options, each compiled without their branches.
    auto pick = [&](auto by_slot_c, auto journal_c, auto candidate_c) {
      auto range = [&](Index begin, Index end, std::size_t part, Index& tested, Index& queries) {
        rows_range<decltype(by_slot_c)::value, decltype(journal_c)::value, decltype(candidate_c)::value>(
            kernel, rows, states, scene, previous, candidate, hit, journal, part, begin, end, tested, queries);
      };
      Index tested = 0, queries = 0;
      if (!parallel(n, threads)) {
        const std::size_t part = journal ? journal->begin_sweep(1) : 0;
        range(0, n, part, tested, queries);
      } else {
        const Index chunks = (n + Kernel::kChunk - 1) / Kernel::kChunk;
        const std::size_t base = journal ? journal->begin_sweep(static_cast<std::size_t>(chunks)) : 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) reduction(+ : tested, queries)
        for (Index c = 0; c < chunks; ++c)
          range(c * Kernel::kChunk, std::min(n, (c + 1) * Kernel::kChunk), base + static_cast<std::size_t>(c), tested, queries);
      }
      return Tally{tested, queries};
    };
    auto with_candidate = [&](auto by_slot_c, auto journal_c) {
      return candidate ? pick(by_slot_c, journal_c, std::true_type{}) : pick(by_slot_c, journal_c, std::false_type{});
    };
    auto with_journal = [&](auto by_slot_c) {
      return journal ? with_candidate(by_slot_c, std::true_type{}) : with_candidate(by_slot_c, std::false_type{});
    };
    const Tally tally = by_slot ? with_journal(std::true_type{}) : with_journal(std::false_type{});
    last_queries = tally.queries;
    return tally;
  }

 private:
  // Rows rows[begin..end) of a sweep (run()), the options fixed at compile time.
  template <bool kBySlot, bool kJournal, bool kCandidate, typename Kernel>
  static void rows_range(const Kernel& kernel, const IndexList& rows, RowStates<typename Kernel::State>& states,
                         const CollisionScene& scene, const Points& previous,
                         const std::vector<std::uint8_t>* candidate, std::vector<std::uint8_t>& hit,
                         Journal<typename Kernel::State>* journal, std::size_t part, Index begin, Index end,
                         Index& tested, Index& queries) {
    typename Kernel::State* const stored = states.stored_data();
    Index t = 0, m_sum = 0;
    for (Index q = begin; q < end; ++q) {
      const Index r = rows[q];
      const TestPoint pt = row_point(scene, previous, r);
      auto& s = kBySlot ? stored[q] : states[r];
      typename Kernel::State before;
      if constexpr (kJournal) before = s;
      Index made;
      if (kCandidate && !(*candidate)[r]) {
        made = kernel.not_candidate(s, pt);
      } else {
        made = kernel.update(s, pt);
      }
      if constexpr (kJournal) journal->note(r, before, s, made, part);
      hit[q] = s.colliding();  // read while the state is in cache
      m_sum += made;
      t += made > 0;
    }
    tested += t;
    queries += m_sum;
  }
};

// Snapshots of per-row states: count, capacity, then each state through put_state / get_state (one
// overload per kernel State, kernel_snapshot.hpp; field by field, never padding bytes).
template <typename State>
void put_states(SnapshotWriter& out, const std::vector<State>& states) {
  out.u64(states.size());
  out.u64(states.capacity());
  for (const State& s : states) put_state(out, s);
}
template <typename State>
std::vector<State> get_states(SnapshotReader& in) {
  const std::size_t n = in.count("detector states", 1);
  std::vector<State> states;
  states.reserve(in.capacity("detector states", n, sizeof(State)));
  states.resize(n);
  for (State& s : states) get_state(in, s);
  return states;
}
// A RowStates: its row -> slot map (each row's slot, -1 without a state), then its states.
template <typename State>
void put_states(SnapshotWriter& out, const RowStates<State>& states) {
  out.vec(states.slots());
  put_states(out, states.dense());
}
template <typename State>
RowStates<State> get_row_states(SnapshotReader& in) {
  std::vector<Index> slots = in.vec<Index>("detector state slots");
  std::vector<State> dense = get_states<State>(in);
  Index next = 0;
  for (Index s : slots) {
    if (s == -1) continue;
    if (s != next) in.fail("detector state slots", "not the states in row order");
    ++next;
  }
  if (static_cast<std::size_t>(next) != dense.size()) in.fail("detector state slots", "count differs from the states");
  RowStates<State> out;
  out.adopt(std::move(slots), std::move(dense));
  return out;
}
// Rows of a snapshot: ascending, in [0, rows).
void check_rows(SnapshotReader& in, const IndexList& list, Index rows, const char* what);

// A kernel's reset_rows() when it has one (Robust), none otherwise.
template <typename K>
auto kernel_reset_rows(const K& kernel, int) -> decltype(kernel.reset_rows()) {
  return kernel.reset_rows();
}
template <typename K>
CollisionDetector::ResetRows kernel_reset_rows(const K&, long) {
  return {};
}

template <typename Kernel, typename Sweep = ParallelSweep>
class RowDetector final : public NarrowDetector {
 public:
  explicit RowDetector(const CollisionParams& params)
      : NarrowDetector(params), rows_(params), sweep_(params), journal_sweep_(params) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    const int threads = resolve_threads(params_.threads);
    IndexList zero_rows;
    KernelRows<Kernel> rows = KernelRows<Kernel>::build(params_, scene, threads, zero_rows);
    rows.kernel.seed(scene, rows.deformable, zero_rows, threads, rows.states);
    rows_ = std::move(rows);
    sweep_.reset();
    journal_.on = false;
    preprocess_ms_ = ms_since(start);
  }

  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* candidate) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    rows_.kernel.bind(scene);
    hit_.resize(rows_.deformable.size());
    const Tally tally = sweep(rows_.deformable, scene, previous, candidate);
    CollisionResult result;
    result.stats.tested = tally.tested;
    result.stats.queries = tally.queries;
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
  }
  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    journal_.on = false;
    rows_.on_inserted(scene, parents);
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
    return rows_.kernel.on_rigid_moved(scene, rows, before, rows_.deformable, rows_.states,
                                       resolve_threads(params_.threads));
  }
  std::size_t memory_bytes() const override {
    return rows_.memory_bytes() + hit_.capacity() + journal_.saved.capacity();
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
  }
  CollisionResult detect_only(const CollisionScene& scene, const Points& previous,
                              const std::vector<std::uint8_t>& candidate) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    rows_.kernel.bind(scene);
    IndexList rows;
    for (Index r : rows_.deformable)
      if (candidate[static_cast<std::size_t>(r)]) rows.push_back(r);
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
    out->preprocess_ms_ = preprocess_ms_;
    return out;
  }

  // The journal (independent points only: an order-dependent sweep saves images before the step). When
  // most rows changed at the last journal (e.g. Robust moves every point's last free position), copying
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
                        journal ? &journal_ : nullptr);
    } else {
      return sweep_.run(rows_.kernel, rows, rows_.states, scene, previous, candidate, threads, hit_);
    }
  }

  KernelRows<Kernel> rows_;
  Sweep sweep_;
  std::vector<std::uint8_t> hit_;  // #deformable: colliding after the last step (filled by the sweep)
  double preprocess_ms_ = 0.0;  // the last reset
  Journal<typename Kernel::State> journal_;  // states before the first change since start_journal()
  Sweep journal_sweep_;                     // the sweep's tallies at start_journal()
  static constexpr int kDenseSkip = 7;      // steps without saved states after a dense journal
  int dense_skip_ = 0;                      // steps left before the journal saves states again
};

}  // namespace surfeledit::detail
