// A binary bounding volume hierarchy over a subset of a model's surfels, with the box kind chosen
// at compile time (thesis §7.3.2: templates, no virtual calls in the hot path). Box kinds: Aabb,
// Obb, Sphere. A Box provides
//   static Box fit(positions, radii, rows, n)          tight box over the balls of rows (kDeadRow skipped)
//   static Vec3 split_direction(box, positions, rows, n) unit axis the build splits along
//   expand(p, r), enclose(child), inflate(m), enforce_min_extent(e), contains(p, r), contains(child)
//   grow_over_child(child) and kContainsChildren   how a parent is made "at least as large" (thesis §10.1.1)
//
// Layout: nodes in one flat array; the children of a node are adjacent (first_child, first_child + 1)
// and always have larger indices than their parent, so a reverse sweep visits children before
// parents. Every node covers a range of slots of `order()`, a permutation of the tree's rows.
//
// Invariants (checked by the property tests): every live box contains the balls (position, radius)
// of all surfels under it, and every parent contains its children (Box::kContainsChildren; OBB
// parents are only at least as large, see obb.hpp) -- after the build, after each bottom-up refit,
// and for the nodes a top-down refit has visited in the current step.
//
// Deforming trees (Box = Aabb): refit() starts a step; with UpdateMode TopDown / Hybrid the deeper
// nodes are refit when a traversal calls touch() on them. Removed surfels are marked dead and dropped
// at the next refit of their leaf; inserted surfels join the leaf of the surfel they were split
// from, whose box (and its ancestors') grows to cover them until the next rebuild.
//
// Compiled once: the member definitions are in bvh-inl.hpp and instantiated for the three box kinds
// in src/bvh/bvh.cpp; the `extern template` lines at the end keep includers from instantiating them
// again. A new box kind adds its instantiation there. Only for_each_row (takes any callable) and
// the fast path of touch() (called per visited node) stay in this header.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "surfeledit/core/bvh/aabb.hpp"
#include "surfeledit/core/bvh/counters.hpp"
#include "surfeledit/core/bvh/obb.hpp"
#include "surfeledit/core/bvh/params.hpp"
#include "surfeledit/core/bvh/sphere.hpp"

namespace surfeledit::bvh {

// One node of a Bvh: its box, its children and the slots of the rows under it.
template <class Box>
struct BvhNode {
  Box box;                        // bounds the balls of every live surfel under this node
  std::int32_t first_child = -1;  // index of the left child; the right one is first_child + 1; -1 = leaf
  std::int32_t parent = -1;       // index of the parent; -1 for the root
  std::int32_t begin = 0;         // first slot of order() under this node
  std::int32_t end = 0;           // one past the last slot (a leaf's live rows are compacted to the front)
  std::int32_t level = 0;         // depth, root = 0

  bool leaf() const { return first_child < 0; }
  std::int32_t size() const { return end - begin; }  // surfel count used by the descend rule (Code 8.4)
};

template <class Box>
class Bvh {
 public:
  using Node = BvhNode<Box>;

  Bvh() = default;
  // Builds over `rows` (indices into `positions` / `radii`; `radii` may be empty = radius 0).
  Bvh(const Points& positions, const Values& radii, const IndexList& rows, const BvhParams& params = {}) {
    build(positions, radii, rows, params);
  }

  // Top-down build (docs/algorithms.md §5 "Build"): split the node's split_direction at the mean of the
  // projected positions; stop at max_level or at <= leaf_max_surfels; a child never gets fewer than
  // leaf_min_surfels. Then leaf boxes get min_leaf_extent and parents are grown over their children.
  void build(const Points& positions, const Values& radii, const IndexList& rows, const BvhParams& params);
  // Takes a tree built elsewhere in this layout (e.g. a sphere cluster tree): `nodes` (root 0, children
  // adjacent and after their parent, ranges over slots of `order`) and `order` (the rows). Rebuilds the
  // per-row leaf map and the step arrays; `params` are kept for later refits. Throws Internal naming the
  // node when the layout is broken. Boxes are taken as they are (they must bound their surfels' balls).
  void adopt(std::vector<Node> nodes, IndexList order, const BvhParams& params);

  const BvhParams& params() const { return params_; }
  const std::vector<Node>& nodes() const { return nodes_; }
  const Node& node(std::int32_t i) const { return nodes_[static_cast<std::size_t>(i)]; }
  const Box& box(std::int32_t i) const { return nodes_[static_cast<std::size_t>(i)].box; }
  const IndexList& order() const { return order_; }
  bool empty() const { return nodes_.empty(); }
  int height() const { return height_; }                  // number of levels (0 when empty)
  Index surfel_count() const { return live_; }            // live surfels, inserted ones included
  double build_ms() const { return build_ms_; }           // wall time of the last build
  // True once a refit, insertion or removal has changed the tree since the last build
  // (the thesis's hasBeenUpdated: a rebuild would fit tighter).
  bool refit_since_build() const { return refit_since_build_; }
  std::size_t memory_bytes() const;

  // Calls f(row) for each live surfel under `node` (inserted ones included).
  template <class F>
  void for_each_row(std::int32_t node, F&& f) const;

  // ---- deforming AABB trees ------------------------------------------------------------------
  // Starts a step: bottom-up part of the refit for the current mode (see UpdateMode). The arrays
  // must stay alive and unchanged until the next refit(), since touch() reads them.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  BvhCounters refit(const Points& positions, const Values& radii);
  // Top-down part: refits `node` from its surfels if it is below the bottom-up levels and was not
  // refit in this step yet (then grows its ancestors over it if needed). Cheap when nothing to do.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  void touch(std::int32_t node, BvhCounters& counters);
  // Refits every node now (a full top-down pass over what touch() would do), e.g. before inspecting boxes.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  void touch_all(BvhCounters& counters);
  std::uint64_t step() const { return step_; }  // incremented by each refit() / step_bounded()

  // ---- bounded update (UpdateMode::Bounded; docs/algorithms.md §5 "Bounded update") -----------
  // A node's box bounds its surfels' balls at the step its `since` value names; at a later step the
  // balls lie in that box grown by (shift() - since) + reach: `shift` sums each step's largest
  // displacement plus largest radius growth of any surfel of the tree, `reach` is this step's largest
  // own displacement |t| (the balls are (p, r + |t|)). No per-row work: a traversal tests bound(node),
  // refits a leaf from its rows when the bound reaches a zero leaf (refit_leaf) and narrows a parent to
  // the union of its children's bounds (tighten). The caller guarantees that `previous` of every step
  // holds the positions of the step before (as EditSession does; undo restores a copy of the tree).
  // Starts a step: `shift` = max over the tree's rows of |p - previous| + max(0, r - r before), `reach` =
  // max |p - previous| (model units, >= 0). The arrays must stay alive and unchanged until the next step.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  BvhCounters step_bounded(const Points& positions, const Points& previous, const Values& radii, double shift,
                           double reach);
  bool bounded() const { return params_.update == UpdateMode::Bounded; }
  bool fitted(std::int32_t node) const { return stamp_[static_cast<std::size_t>(node)] == step_; }  // in this step
  double shift() const { return shift_; }  // the running sum of the steps' shifts
  // The box `node` has in this step: its box when fit or narrowed in this step, else the grown box.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  Aabb bound(std::int32_t node) const;
  // Refits leaf `node` from its rows' balls (p, r + |p - previous|) unless it was in this step; true if it was refit now.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  bool refit_leaf(std::int32_t node, BvhCounters& counters);
  // Narrows inner `node` to its bound intersected with the union of its children's bounds.
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  void tighten(std::int32_t node);
  // The next step_bounded() refits every node from its rows (after adopting a tree built elsewhere).
  void refit_all_next_step() { refit_all_ = true; }

  // ---- step journal (bounded AABB trees: undo of steps, history.hpp) --------------------------
  // A bounded step changes only the nodes it fits or narrows (box, stamp, since: step_bounded's fit of every
  // node, refit_leaf, tighten) and the step's scalars, so the undo image of a step holds those nodes as they
  // were instead of a copy of the tree. Marks are not kept: every traversal starts a new epoch (new_marks), so
  // no mark of an undone step reads as set.
  struct StepImage {
    struct Saved {
      std::int32_t node = 0;    // its index
      std::uint64_t stamp = 0;  // its stamp, since and box before its first change in a step
      double since = 0.0;
      Box box;
    };
    std::vector<Saved> saved;           // in the order of the changes (put back in reverse)
    std::uint64_t step = 0;             // the step scalars when the journal started
    double shift = 0.0, reach = 0.0;
    bool refit_all = false, refit_since_build = false;
    const Points* positions = nullptr;  // the arrays of the step before the journal
    const Points* previous = nullptr;
    const Values* radii = nullptr;
    std::uint64_t step_after = 0;       // the tree's step when the image was taken, and its node count:
    std::size_t node_count = 0;         // restore() takes the image only while they are the tree's
    std::size_t bytes() const { return sizeof(*this) + saved.capacity() * sizeof(Saved); }
  };
  // Starts noting changes (an earlier journal is dropped). False, and no journal, unless this is a bounded
  // AABB tree without dead slots (a leaf's compaction would move rows). build(), adopt(), on_removed(),
  // on_inserted() and stop_journal() end it; a copy of the tree takes it along (see journal_ below); refit() of
  // a journaled tree throws Internal.
  bool start_journal();
  bool journaling() const { return journal_.on; }
  void stop_journal() {
    journal_.on = false;
    journal_.image.saved.clear();
  }
  // The changes since start_journal(): an image restore() takes while the tree is as it is now.
  StepImage journal() const;
  // Whether restore(image) fits this tree: the node count and the step it was taken at.
  bool fits(const StepImage& image) const;
  // Puts the tree back as it was when the image's journal started; Internal, nothing changed, unless it fits.
  void restore(const StepImage& image);
  // restore(journal()) without the copy; the journal goes on (later changes are noted as well).
  void restore_journal();

  // The model dropped rows: `keep` has one flag per old row. Dropped surfels become dead slots
  // (boxes unchanged until their leaf's next refit); kept rows are renumbered.
  void on_removed(const std::vector<bool>& keep);
  // The model appended parents.size() rows after its existing ones (row = positions.rows() -
  // parents.size() + k was split from parents[k]). Each joins its parent's leaf, whose box and
  // ancestors grow to cover it. Children of rows not in this tree are ignored.
  BvhCounters on_inserted(const Points& positions, const Values& radii, const IndexList& parents);

  // ---- tree/tree marks (Code 8.4) ------------------------------------------------------------
  // Starts a new marking epoch: every node is unmarked at once.
  void new_marks() {
    if (++mark_ == 0) {
      std::fill(marks_.begin(), marks_.end(), 0u);
      mark_ = 1;
    }
  }
  bool marked(std::int32_t n) const { return marks_[static_cast<std::size_t>(n)] == mark_; }
  void set_mark(std::int32_t n) { marks_[static_cast<std::size_t>(n)] = mark_; }

 private:
  Node& mut(std::int32_t i) { return nodes_[static_cast<std::size_t>(i)]; }
  // build() and adopt(), once nodes_ and order_ are set: a tree with no step, insertion or removal
  // behind it (params_ = params, live_ = order_.size(), height_ = 0) ...
  void reset_steps(const BvhParams& params);
  // ... then the leaf of every row (leaf_of_row_) and the per-node step and mark arrays.
  void index_nodes();
  // Slow path of touch(): `node` was not refit in this step yet (its stamp is already set).
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  void refit_touched(std::int32_t node, BvhCounters& counters);
  void compact_leaf(std::int32_t leaf);
  // Before a journaled change of node k (box, stamp, since): keeps it at its first change in this step.
  void note(std::size_t k) {
    if (journal_.on && stamp_[k] != step_)
      journal_.image.saved.push_back({static_cast<std::int32_t>(k), stamp_[k], since_[k], nodes_[k].box});
  }
  // The journal's nodes in reverse, then its start scalars (restore(), restore_journal()).
  void put_back(const StepImage& image);
  Aabb tight_aabb(std::int32_t node) const;
  unsigned refit_axes(Aabb& box, const Aabb& tight, unsigned axes) const;
  void grow_ancestors(std::int32_t node);
  int bottom_up_levels() const;
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  Aabb tight_reach(std::int32_t node) const;  // tight box over the balls (p, r + |p - previous|) of `node`
  template <class B = Box, class = std::enable_if_t<std::is_same_v<B, Aabb>>>
  void fit_all_bounded(BvhCounters& counters);  // every node from its rows, leaves up (step_bounded)

  BvhParams params_;
  std::vector<Node> nodes_;
  IndexList order_;                        // slots: a permutation of the tree's rows, kDeadRow when removed
  std::vector<std::int32_t> leaf_of_row_;  // by model row: its leaf, -1 if not in this tree
  // Inserted surfels: singly linked list per leaf (head by node, next and row by entry).
  std::vector<std::int32_t> extra_head_, extra_next_;
  IndexList extra_row_;
  Index extras_ = 0;                       // live inserted surfels
  Index dead_ = 0;                         // surfels removed since the build (their slots may linger)
  Index live_ = 0;
  int height_ = 0;
  double build_ms_ = 0.0;
  bool refit_since_build_ = false;
  // Step state of a deforming tree.
  std::uint64_t step_ = 0;
  std::vector<std::uint64_t> stamp_;       // step in which a node was last refit
  std::vector<std::uint8_t> masks_;        // scratch: axes a node changed in the bottom-up sweep
  int cut_ = 0;                            // nodes with level < cut_ are refit bottom-up
  const Points* positions_ = nullptr;      // arrays of the current step (for touch)
  const Values* radii_ = nullptr;
  // Bounded update (step_bounded).
  const Points* previous_ = nullptr;       // positions before the current step
  std::vector<double> since_;              // by node: shift_ when its box was last fit or narrowed
  double shift_ = 0.0;                     // running sum of the steps' shifts (model units)
  double reach_ = 0.0;                     // this step's largest own displacement (model units)
  bool refit_all_ = false;                 // the next step_bounded() fits every node
  // Marks of the tree/tree traversal.
  std::vector<std::uint32_t> marks_;
  std::uint32_t mark_ = 1;
  // Step journal: whether one runs, its start scalars and the nodes noted since (step scratch: not in
  // memory_bytes()). A copy of the tree takes it along, so a copy taken during a journal and assigned back
  // within it leaves a journal that still leads back to the start (a back-off's image of a few rows).
  struct Journal {
    bool on = false;
    StepImage image;
  };
  Journal journal_;
};

template <class Box>
template <class F>
void Bvh<Box>::for_each_row(std::int32_t node, F&& f) const {
  const Node& nd = nodes_[static_cast<std::size_t>(node)];
  for (std::int32_t s = nd.begin; s < nd.end; ++s)
    if (order_[s] >= 0) f(order_[s]);
  if (extras_ == 0) return;
  // Inserted surfels hang off leaves: walk the leaves under `node`.
  std::int32_t stack_buf[128];
  int top = 0;
  stack_buf[top++] = node;
  while (top > 0) {
    const std::int32_t i = stack_buf[--top];
    const Node& x = nodes_[static_cast<std::size_t>(i)];
    if (x.leaf()) {
      for (std::int32_t e = extra_head_[i]; e >= 0; e = extra_next_[e])
        if (extra_row_[e] >= 0) f(extra_row_[e]);
    } else {
      stack_buf[top++] = x.first_child;
      stack_buf[top++] = x.first_child + 1;
    }
  }
}

template <class Box>
template <class B, class>
void Bvh<Box>::touch(std::int32_t node, BvhCounters& counters) {
  const std::size_t k = static_cast<std::size_t>(node);
  if (stamp_[k] == step_) return;
  stamp_[k] = step_;
  refit_touched(node, counters);
}

// Instantiated once, in src/bvh/bvh.cpp.
extern template class Bvh<Aabb>;
extern template class Bvh<Obb>;
extern template class Bvh<Sphere>;
extern template BvhCounters Bvh<Aabb>::refit<Aabb, void>(const Points&, const Values&);
extern template void Bvh<Aabb>::refit_touched<Aabb, void>(std::int32_t, BvhCounters&);
extern template void Bvh<Aabb>::touch_all<Aabb, void>(BvhCounters&);
extern template BvhCounters Bvh<Aabb>::step_bounded<Aabb, void>(const Points&, const Points&, const Values&, double,
                                                                 double);
extern template bool Bvh<Aabb>::refit_leaf<Aabb, void>(std::int32_t, BvhCounters&);
extern template void Bvh<Aabb>::tighten<Aabb, void>(std::int32_t);
extern template Aabb Bvh<Aabb>::bound<Aabb, void>(std::int32_t) const;

}  // namespace surfeledit::bvh
