// The row detector's undo journal (row_detector.hpp, history.hpp): the states of the rows its sweeps changed,
// as they were when the journal started.
#pragma once

#include <algorithm>
#include <cstring>
#include <vector>

#include "kernel_rows.hpp"

namespace surfeledit::detail {

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
  // A state's bytes as taken before an update, in 8-byte words. A plain State copy lets the compiler store its
  // small fields one by one, and the wider loads of note()'s comparison then cannot be forwarded from those
  // stores: a stall of every journaled row (RESULTS §71).
  struct Image {
    static_assert(sizeof(State) % 8 == 0, "a state is a whole number of 8-byte words");
    std::uint64_t word[sizeof(State) / 8];
    [[gnu::always_inline]] static Image of(const State& s) {
      Image b;
      std::memcpy(b.word, &s, sizeof(State));
      return b;
    }
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
  void note(Index r, const Image& before, const State& after, Index queries, std::size_t part) {
    if (queries > 0) tested[static_cast<std::size_t>(r)] = 1;
    if (!save || std::memcmp(before.word, &after, sizeof(State)) == 0) return;
    if (sweeps > 1) {
      if (saved[static_cast<std::size_t>(r)]) return;
      saved[static_cast<std::size_t>(r)] = 1;
    }
    Saved& e = parts[part].emplace_back();
    e.row = r;
    std::memcpy(static_cast<void*>(&e.state), before.word, sizeof(State));
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

}  // namespace surfeledit::detail
