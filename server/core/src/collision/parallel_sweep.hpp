// The row detector's sweep over independent points (row_detector.hpp): serial or in OpenMP chunks, by the
// previous step's estimated work; results do not depend on either.
#pragma once

#include <algorithm>
#include <cstring>
#include <exception>
#include <string>
#include <type_traits>
#include <vector>

#include "kernel_rows.hpp"
#include "row_journal.hpp"

namespace surfeledit::detail {

// Nearest-neighbour queries and points tested in one step.
struct Tally {
  Index tested = 0;   // points whose state was (re)evaluated (queries > 0)
  Index queries = 0;  // nearest-neighbour queries made
};

// Whether a kernel has probes (kernel.hpp: Probe, probing(), probe(), update(s, pt, found)).
template <typename Kernel, typename = void>
inline constexpr bool kProbes = false;
template <typename Kernel>
inline constexpr bool kProbes<Kernel, std::void_t<typename Kernel::Probe>> = true;

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
        auto chunk = [&](Index c, Index& t, Index& m) {
          range(c * Kernel::kChunk, std::min(n, (c + 1) * Kernel::kChunk), base + static_cast<std::size_t>(c), t, m);
        };
        if constexpr (kChecked) {
          // The check below throws, and an exception must not leave an OpenMP region (std::terminate): the lowest
          // chunk's is kept and thrown after it, the same one whatever the threads. A release build's sweep throws
          // nothing (its inputs are checked before), so its loop stays as it was.
          std::exception_ptr error;
          Index error_chunk = chunks;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) reduction(+ : tested, queries)
          for (Index c = 0; c < chunks; ++c) {
            try {
              chunk(c, tested, queries);
            } catch (...) {
#pragma omp critical(surfeledit_sweep_error)
              if (c < error_chunk) {
                error_chunk = c;
                error = std::current_exception();
              }
            }
          }
          if (error) std::rethrow_exception(error);
        } else {
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) reduction(+ : tested, queries)
          for (Index c = 0; c < chunks; ++c) chunk(c, tested, queries);
        }
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
