// Per-row detector states in snapshots (row_detector.hpp, kernel_snapshot.hpp).
#pragma once

#include <utility>
#include <vector>

#include "kernel_rows.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit::detail {

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

}  // namespace surfeledit::detail
