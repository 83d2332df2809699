// The row detector's sweep over independent points (row_detector.hpp): serial or in chunks shared among threads
// (share_chunks.hpp), by the previous step's estimated work; results do not depend on either.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "../share_chunks.hpp"
#include "kernel_rows.hpp"
#include "row_journal.hpp"

namespace surfeledit::detail {

// Nearest-neighbour queries and points tested in one step.
struct Tally {
  Index tested = 0;   // points whose state was (re)evaluated (queries > 0)
  Index queries = 0;  // nearest-neighbour queries made
  Index asleep = 0;   // points of sleeping blocks (SleepingBlocks): not read
};

// Whether a kernel has probes (kernel.hpp: Probe, probing(), probe(), update(s, pt, found)).
template <typename Kernel, typename = void>
inline constexpr bool kProbes = false;
template <typename Kernel>
inline constexpr bool kProbes<Kernel, std::void_t<typename Kernel::Probe>> = true;
// Whether a kernel names quiet spheres (kernel.hpp: quiet_sphere()).
template <typename Kernel, typename = void>
inline constexpr bool kQuiet = false;
template <typename Kernel>
inline constexpr bool kQuiet<Kernel, std::void_t<decltype(Kernel::quiet_sphere(
                                         std::declval<const typename Kernel::State&>()))>> = true;

// Sleeping blocks: most rows of a step stay inside their spheres, where their updates change nothing, and a step
// with a displacement bound (CollisionScene::displacement_bound: no row moved farther since the last sweep) lets a
// block of rows that all stay that far inside sleep without being read. After each sweep of a block its budget is a
// lower bound on how far every row of it may move and stay strictly inside its quiet sphere (kernel.hpp); a
// sleeping step takes the bound off it, and a block whose budget is not above the step's bound is swept. Results are
// the sweep's, bit for bit: a sleeping row's update would have left its state as it is and it does not collide.
// Valid only for a sweep of the detector's whole deformable list in order with the positions of its last sweep;
// the detector clears the budgets whenever its states or rows change otherwise (RESULTS §84).
struct SleepingBlocks {
  static constexpr Index kBlock = 32;  // rows per block (consecutive rows of the deformable list)
  std::vector<double> budget;          // per block, model units; 0: swept at the next step
  // Every block swept at the next step.
  void clear() { std::fill(budget.begin(), budget.end(), 0.0); }
  // One budget of 0 per block of `rows` rows, at exactly that capacity.
  void size_for(std::size_t rows) {
    budget = std::vector<double>((rows + static_cast<std::size_t>(kBlock) - 1) / static_cast<std::size_t>(kBlock), 0.0);
  }
  std::size_t memory_bytes() const { return budget.capacity() * sizeof(double); }

  // The budget of rows [0, n) (states `s`, their rows `row`): the least rho - |p - c| of their quiet spheres, less a
  // guard for the rounding of these and of the next steps' tests (1e-12 of the coordinates' and the spheres' size); 0
  // when a row has no quiet sphere or is not strictly inside it, or (without its square roots) when one has
  // rho^2 - |p - c|^2 < cut^2, so rho - |p - c| < cut: a block that would not sleep through a step of `cut` anyway.
  template <typename Kernel>
  static double budget_of(const typename Kernel::State* s, const Index* row, const StepRows& at, Index n, double cut) {
    double least = std::numeric_limits<double>::infinity(), size = 0.0;
    const double cut2 = cut * cut;
    for (Index i = 0; i < n; ++i) {
      const Sphere* q = Kernel::quiet_sphere(s[i]);
      if (!q) return 0.0;
      const Vec3 p = at(row[i]).p;
      const double d2 = (p - q->center).squaredNorm();
      if (!(q->rho2 - d2 > cut2)) return 0.0;
      const double rho = std::sqrt(q->rho2), slack = rho - std::sqrt(d2);
      if (!(slack > 0.0)) return 0.0;
      least = std::min(least, slack);
      size = std::max(size, std::max(p.cwiseAbs().maxCoeff(), rho));
    }
    const double b = least - 1e-12 * size;
    return b > 0.0 ? b : 0.0;
  }
};

// The points of a step are independent: each row goes through update() (not_candidate() when the
// broad phase ruled it out), in chunks of Kernel::kChunk rows shared among threads (share_chunks) when the
// step's work is large enough to pay for waking the other threads, else serially. Results do not depend on
// either.
// Every sweep also fills hit[q] (#rows): 1 when rows[q] collides after the step.
//
// The work is not known before the step, so the previous step's stands for it (steps of one drag are
// alike): `rows` x kRowNs + its nearest-neighbour queries x kQueryNs, from one-thread profiles of the
// Robust step (RESULTS §23: ~5 ns a row that stays in its sphere, ~0.37 us a query). Below kParallelNs a
// step runs on one thread: waking a helper costs little on an idle machine, but on a busy one a helper that
// is descheduled holding a chunk makes the step wait for the scheduler's next tick (an OpenMP region waited so
// for every worker: steps of 0.3 ms took 4, 8 or 16 ms, RESULTS §35), which only work of a millisecond or more
// can hide. The threshold is the setting parallel_min_ms.
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
  // `sleep` (may be null; only with `by_slot` and a kernel with quiet spheres): the sleeping blocks, which a step with
  // scene.displacement_bound lets sleep.
  template <typename Kernel>
  Tally run(const Kernel& kernel, const IndexList& rows, RowStates<typename Kernel::State>& states,
            const CollisionScene& scene, const Points& previous, const std::vector<std::uint8_t>* candidate,
            int threads, std::vector<std::uint8_t>& hit, bool by_slot,
            Journal<typename Kernel::State>* journal = nullptr, SleepingBlocks* sleep = nullptr) {
    const Index n = static_cast<Index>(rows.size());
    if (by_slot && states.stored() != rows.size()) throw Error(ErrorCode::Internal, "rows", "not one per state");
    constexpr Index kBlock = SleepingBlocks::kBlock;
    static_assert(Kernel::kChunk % kBlock == 0, "a chunk holds whole sleeping blocks");
    if constexpr (!kQuiet<Kernel>) sleep = nullptr;
    if (!by_slot) sleep = nullptr;
    const std::size_t blocks = static_cast<std::size_t>((n + kBlock - 1) / kBlock);
    if (sleep && sleep->budget.size() != blocks) sleep = nullptr;  // not sized for this list: no sleep
    // The step's bound, or -1: every block swept (and its budget taken afresh).
    const double bound = sleep && scene.displacement_bound ? *scene.displacement_bound : -1.0;
    // One loop per combination of the three options, each compiled without their branches.
    auto pick = [&](auto by_slot_c, auto journal_c, auto candidate_c) {
      auto awake = [&](Index begin, Index end, std::size_t part, Index& tested, Index& queries) {
        rows_range<decltype(by_slot_c)::value, decltype(journal_c)::value, decltype(candidate_c)::value>(
            kernel, rows, states, scene, previous, candidate, hit, journal, part, begin, end, tested, queries);
      };
      // Rows [begin, end) (whole blocks but at the list's end): each run of blocks that do not sleep swept at once,
      // then their budgets taken.
      auto range = [&](Index begin, Index end, std::size_t part, Index& tested, Index& queries, Index& asleep) {
        if constexpr (kQuiet<Kernel>) {
          if (sleep) {
            const StepRows at(scene, previous);
            const auto* stored = states.stored_data();
            // Whether the block of row e sleeps this step.
            auto sleeps = [&](Index e) { return bound >= 0.0 && bound < sleep->budget[static_cast<std::size_t>(e / kBlock)]; };
            for (Index b = begin; b < end;) {
              Index e = b;
              for (; e < end && !sleeps(e); e += kBlock) {
              }
              e = std::min(e, end);
              if (e > b) {
                awake(b, e, part, tested, queries);
                for (Index c = b; c < e; c += kBlock) {
                  sleep->budget[static_cast<std::size_t>(c / kBlock)] = SleepingBlocks::budget_of<Kernel>(
                      stored + c, rows.data() + c, at, std::min(kBlock, e - c), std::max(bound, 0.0));
                }
              }
              for (; e < end && sleeps(e); e += kBlock) {
                const Index f = std::min(end, e + kBlock);
                if constexpr (kChecked) asleep_check(kernel, stored, rows, at, e, f);
                sleep->budget[static_cast<std::size_t>(e / kBlock)] -= bound;
                std::memset(hit.data() + e, 0, static_cast<std::size_t>(f - e));
                asleep += f - e;
              }
              b = e;
            }
            return;
          }
        }
        awake(begin, end, part, tested, queries);
      };
      Index tested = 0, queries = 0, asleep = 0;
      if (!parallel(n, threads)) {
        const std::size_t part = journal ? journal->begin_sweep(1) : 0;
        range(0, n, part, tested, queries, asleep);
      } else {
        const Index chunks = (n + Kernel::kChunk - 1) / Kernel::kChunk;
        const std::size_t base = journal ? journal->begin_sweep(static_cast<std::size_t>(chunks)) : 0;
        // Each chunk's counts apart (summed below in chunk order); a release build's sweep throws nothing (its
        // inputs are checked before); a checked build's lowest throwing chunk is rethrown (share_chunks).
        std::vector<Tally> counts(static_cast<std::size_t>(chunks));
        share_chunks(threads, chunks, [&](Index c) {
          Tally& t = counts[static_cast<std::size_t>(c)];
          range(c * Kernel::kChunk, std::min(n, (c + 1) * Kernel::kChunk), base + static_cast<std::size_t>(c),
                t.tested, t.queries, t.asleep);
        });
        for (const Tally& t : counts) {
          tested += t.tested;
          queries += t.queries;
          asleep += t.asleep;
        }
      }
      return Tally{tested, queries, asleep};
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
  // A checked build (kChecked) checks that the rows of a sleeping block stay strictly inside their quiet spheres, so
  // that their updates would have changed nothing.
  template <typename Kernel>
  static void asleep_check(const Kernel&, const typename Kernel::State* stored, const IndexList& rows,
                           const StepRows& at, Index begin, Index end) {
    for (Index q = begin; q < end; ++q) {
      const Sphere* s = Kernel::quiet_sphere(stored[q]);
      if (!s || !s->contains(at(rows[static_cast<std::size_t>(q)]).p))
        throw Error(ErrorCode::Internal, "SleepingBlocks",
                    "row " + std::to_string(rows[static_cast<std::size_t>(q)]) + " left its quiet sphere while asleep");
    }
  }
  // Rows rows[begin..end) of a sweep (run()), the options fixed at compile time.
  template <bool kBySlot, bool kJournal, bool kCandidate, typename Kernel>
  static void rows_range(const Kernel& kernel, const IndexList& rows, RowStates<typename Kernel::State>& states,
                         const CollisionScene& scene, const Points& previous,
                         const std::vector<std::uint8_t>* candidate, std::vector<std::uint8_t>& hit,
                         Journal<typename Kernel::State>* journal, std::size_t part, Index begin, Index end,
                         Index& tested, Index& queries) {
    if constexpr (kProbes<Kernel>) {
      if (kernel.probing())
        return probed_range<kBySlot, kJournal, kCandidate>(kernel, rows, states, scene, previous, candidate, hit,
                                                           journal, part, begin, end, tested, queries);
    }
    typename Kernel::State* const stored = states.stored_data();
    const StepRows at(scene, previous);
    const Index* const row = rows.data();
    const std::uint8_t* const cand = candidate ? candidate->data() : nullptr;
    std::uint8_t* const hits = hit.data();
    Index t = 0, m_sum = 0;
    for (Index q = begin; q < end; ++q) {
      const Index r = row[q];
      const TestPoint pt = at(r);
      auto& s = kBySlot ? stored[q] : states[r];
      row_step<kJournal, kCandidate>(kernel, q, r, s, pt, cand, hits, journal, part, t, m_sum,
                                     [&] { return kernel.update(s, pt); });
    }
    tested += t;
    queries += m_sum;
  }

  // One row of a sweep: update() (`update`) or not_candidate(), the journal's note, the row's hit flag (read while
  // the state is in cache), the tallies.
  template <bool kJournal, bool kCandidate, typename Kernel, typename Update>
  [[gnu::always_inline]] static void row_step(const Kernel& kernel, Index q, Index r, typename Kernel::State& s,
                                              const TestPoint& pt, const std::uint8_t* candidate, std::uint8_t* hit,
                                              Journal<typename Kernel::State>* journal, std::size_t part, Index& t,
                                              Index& m_sum, Update update) {
    typename Journal<typename Kernel::State>::Image before;
    if constexpr (kJournal) before = Journal<typename Kernel::State>::Image::of(s);
    const Index made = row_update<kCandidate>(kernel, q, r, s, pt, candidate, hit, t, m_sum, update);
    if constexpr (kJournal) journal->note(r, before, s, made, part);
  }
  // row_step() without the journal's note; returns the queries made.
  template <bool kCandidate, typename Kernel, typename Update>
  [[gnu::always_inline]] static Index row_update(const Kernel& kernel, Index q, Index r, typename Kernel::State& s,
                                                 const TestPoint& pt, const std::uint8_t* candidate, std::uint8_t* hit,
                                                 Index& t, Index& m_sum, Update update) {
    const Index made = kCandidate && !candidate[r] ? kernel.not_candidate(s, pt) : update();
    hit[q] = s.colliding();
    m_sum += made;
    t += made > 0;
    return made;
  }

  // rows_range() for a kernel with probes (kernel.hpp), kProbeBlock rows at a time: first the searches of the
  // block's rows that will be tested (the kernel asks for the cache lines of what they found), the other rows updated
  // there and then, while their states are in cache; then the tested rows' updates in order with what their searches
  // found, so a row's reads do not wait on memory right after its search. The journal's notes are taken in the
  // second pass, in row order as rows_range() takes them (each row's state as it was before the first pass), of
  // every row but those whose update the kernel says keeps their state (Kernel::keeps, keeps_not_candidate).
  static constexpr Index kProbeBlock = 32;
  // A checked build (SURFELEDIT_CHECKED; on with the sanitizers' build in scripts/test.sh) also takes the image of
  // every row whose update the kernel says keeps its state and throws when its bytes changed: the journal would
  // have missed that row, and the results-based tests cannot see it.
#ifdef SURFELEDIT_CHECKED
  static constexpr bool kChecked = true;
#else
  static constexpr bool kChecked = false;
#endif
  static constexpr Index kAhead = 24;  // rows: the state read that far ahead is asked for
  template <bool kBySlot, bool kJournal, bool kCandidate, typename Kernel>
  static void probed_range(const Kernel& kernel, const IndexList& rows, RowStates<typename Kernel::State>& states,
                           const CollisionScene& scene, const Points& previous,
                           const std::vector<std::uint8_t>* candidate, std::vector<std::uint8_t>& hit,
                           Journal<typename Kernel::State>* journal, std::size_t part, Index begin, Index end,
                           Index& tested, Index& queries) {
    using Image = typename Journal<typename Kernel::State>::Image;
    typename Kernel::State* const stored = states.stored_data();
    const StepRows at(scene, previous);
    const Index* const row = rows.data();
    const std::uint8_t* const cand = candidate ? candidate->data() : nullptr;
    std::uint8_t* const hits = hit.data();
    typename Kernel::Probe found[kProbeBlock];
    bool probed[kProbeBlock];
    Index made[kJournal ? kProbeBlock : 1];   // the untested rows' queries (not_candidate() may make some)
    Image before[kJournal ? kProbeBlock : 1];
    bool noted[kJournal ? kProbeBlock : 1];   // the row may change: its before-image is taken and noted
    Index t = 0, m_sum = 0;
    for (Index b = begin; b < end; b += kProbeBlock) {
      const Index e = std::min(end, b + kProbeBlock);
      for (Index q = b; q < e; ++q) {
        const Index r = row[q], k = q - b;
        auto& s = kBySlot ? stored[q] : states[r];
        if constexpr (kBySlot) __builtin_prefetch(stored + std::min(q + kAhead, end - 1));
        const TestPoint pt = at(r);
        const bool candidate_row = !(kCandidate && !cand[r]);
        probed[k] = candidate_row && kernel.probe(s, pt, found[k]);  // reads the state only
        if constexpr (kJournal) {
          noted[k] = probed[k] || !(candidate_row ? kernel.keeps(s) : kernel.keeps_not_candidate(s, pt));
          if (noted[k] || kChecked) before[k] = Image::of(s);
        }
        if (probed[k]) continue;
        const Index m = row_update<kCandidate>(kernel, q, r, s, pt, cand, hits, t, m_sum,
                                               [&] { return kernel.update(s, pt, nullptr); });
        if constexpr (kJournal) made[k] = m;
      }
      for (Index q = b; q < e; ++q) {
        const Index r = row[q], k = q - b;
        auto& s = kBySlot ? stored[q] : states[r];
        if (probed[k]) {
          const TestPoint pt = at(r);
          const Index m = row_update<false>(kernel, q, r, s, pt, cand, hits, t, m_sum,
                                            [&] { return kernel.update(s, pt, &found[k]); });
          if constexpr (kJournal) made[k] = m;
        }
        if constexpr (kJournal) {
          if (noted[k]) {
            journal->note(r, before[k], s, made[k], part);
          } else if constexpr (kChecked) {
            if (std::memcmp(before[k].word, &s, sizeof(s)) != 0)
              throw Error(ErrorCode::Internal, "Kernel::keeps",
                          "row " + std::to_string(r) + " changed in an update its kernel said keeps its state");
          }
        }
      }
    }
    tested += t;
    queries += m_sum;
  }
};

}  // namespace surfeledit::detail
