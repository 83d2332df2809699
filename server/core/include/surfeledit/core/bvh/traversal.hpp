// Broad-phase traversals (docs/algorithms.md §5 "Traversal"):
//  - surfel/tree with a FIFO queue, breadth first (thesis Code 7.6);
//  - tree/tree between the zero tree (any box kind) and the deformable AABB tree (Code 8.4):
//    descend the node with more surfels; at a pair of overlapping leaves hand each deformable
//    surfel of the leaf to the narrow-phase policy, at most once per call: tested deformable leaves
//    are marked, and so is a parent whose two children are marked.
// The narrow phase is a policy (any callable `void(Index row)`), e.g. CollectRows below or
// ExtendedNarrow (extended.hpp); the thesis's is the global k-d tree inside/outside test.
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/bvh/overlap.hpp"

namespace surfeledit::bvh {

// Surfel/tree (Code 7.6): calls on_leaf(leaf) for every leaf whose box overlaps the surfel sphere,
// in breadth-first order; stops early when on_leaf returns false. `fifo` is caller-owned scratch
// (reused between queries to avoid allocations). Counts Nv.
template <class Box, class OnLeaf>
void query_surfel(const Bvh<Box>& tree, const Sphere& surfel, OnLeaf&& on_leaf, BvhCounters& counters,
                  std::vector<std::int32_t>& fifo) {
  if (tree.empty()) return;
  fifo.clear();
  fifo.push_back(0);
  for (std::size_t head = 0; head < fifo.size(); ++head) {
    const std::int32_t i = fifo[head];
    const auto& nd = tree.node(i);
    ++counters.nv;
    if (!overlap_surfel(nd.box, surfel)) continue;
    if (nd.leaf()) {
      if (!on_leaf(i)) return;
    } else {
      fifo.push_back(nd.first_child);
      fifo.push_back(nd.first_child + 1);
    }
  }
}

// Convenience: the rows of every leaf the surfel overlaps (candidates for its narrow test).
template <class Box>
IndexList candidate_rows(const Bvh<Box>& tree, const Sphere& surfel, BvhCounters& counters) {
  IndexList rows;
  std::vector<std::int32_t> fifo;
  query_surfel(tree, surfel, [&](std::int32_t leaf) {
    tree.for_each_row(leaf, [&](Index r) { rows.push_back(r); });
    return true;
  }, counters, fifo);
  return rows;
}

// Narrow-phase policy that just collects the candidate deformable rows (each at most once per call).
struct CollectRows {
  IndexList rows;  // candidate deformable rows, in traversal order
  void operator()(Index row) { rows.push_back(row); }
};

namespace detail {

template <class ZeroBox, class Narrow>
struct TreeTree {
  const Bvh<ZeroBox>& zero;
  Bvh<Aabb>& def;
  SatMode sat;
  Narrow& narrow;
  BvhCounters& counters;
  bool bounded;  // def.bounded(): bound() / refit_leaf() / tighten() instead of touch()
  const Aabb* hull;  // box of every zero ball, or nullptr: a deformable box missing it reaches no zero leaf
  using ZeroNode = typename Bvh<ZeroBox>::Node;

  // Whether deformable box b may reach a zero ball at all (the hull is tight where OBB and sphere nodes are
  // loose, e.g. the spheres over a flat plate; an AABB root is the hull already).
  bool in_hull(const Aabb& b) const { return !hull || overlap(*hull, b); }

  // Descends the deformable node d (both children), marking d when both children are marked; a
  // bounded tree then narrows d to its children's bounds (they may have been refit on the way).
  void split_deformable(std::int32_t z, std::int32_t d) {
    const std::int32_t c = def.node(d).first_child;
    run(z, c);
    run(z, c + 1);
    if (def.marked(c) && def.marked(c + 1)) def.set_mark(d);
    if (bounded) def.tighten(d);
  }

  // Whether d's box overlaps zero node z in this step. Bounded trees: the grown box first; a leaf it
  // reaches is refit from its rows and tested again.
  bool overlaps(const ZeroNode& zn, std::int32_t d) {
    ++counters.nv;
    if (!bounded) {
      def.touch(d, counters);  // lazy top-down refit (no-op for bottom-up levels)
      return in_hull(def.box(d)) && overlap(zn.box, def.box(d), sat);
    }
    const Aabb grown = def.bound(d);
    if (!in_hull(grown) || !overlap(zn.box, grown, sat)) return false;
    if (!def.node(d).leaf() || !def.refit_leaf(d, counters)) return true;
    ++counters.nv;
    return in_hull(def.box(d)) && overlap(zn.box, def.box(d), sat);
  }

  void run(std::int32_t z, std::int32_t d) {
    if (def.marked(d)) return;  // every surfel under d was already handed to the narrow phase
    const auto& zn = zero.node(z);
    if (!overlaps(zn, d)) return;
    const auto& dn = def.node(d);
    if (zn.leaf()) {
      if (dn.leaf()) {
        def.set_mark(d);
        def.for_each_row(d, [&](Index row) {
          ++counters.np;
          narrow(row);
        });
        return;
      }
      split_deformable(z, d);
    } else if (dn.leaf() || (dn.size() <= zn.size() && (!bounded || def.fitted(d)))) {
      // (A bounded node not fitted in this step is split first: its children's fits narrow it.)
      run(zn.first_child, d);
      run(zn.first_child + 1, d);
    } else {
      split_deformable(z, d);
    }
  }
};

}  // namespace detail

// Tree/tree (Code 8.4): every deformable surfel in a deformable leaf whose box overlaps a zero leaf
// box is passed once to `narrow`. Starts a new marking epoch of `deformable` (so one call = one
// step's test); lazily refits its nodes (touch, or refit_leaf / tighten of a bounded tree, after its
// step_bounded()) as visited. `hull`, when given, bounds every zero ball: deformable boxes missing it are
// pruned too (no candidate is lost). Counts Nv, Np, Nu.
template <class ZeroBox, class Narrow>
void collide(const Bvh<ZeroBox>& zero, Bvh<Aabb>& deformable, SatMode sat, Narrow& narrow, BvhCounters& counters,
             const Aabb* hull = nullptr) {
  if (zero.empty() || deformable.empty()) return;
  deformable.new_marks();
  detail::TreeTree<ZeroBox, Narrow> t{zero, deformable, sat, narrow, counters, deformable.bounded(), hull};
  t.run(0, 0);
}

}  // namespace surfeledit::bvh
