// Simple Algo as a kernel (§4.1 of docs/algorithms.md, thesis Code 6.1): every step a tested point
// queries its nearest zero surfel and is tested with the §4.1 heuristics (boundary marks, per-point
// step bound). Depth of a colliding point: its distance |d| to that zero surfel (Eq. 6.4).
// Also the zero-region reference that Simple and Temporal share (ZeroSetKernel).
#pragma once

#include <cmath>

#include "kernel.hpp"

namespace surfeledit::detail {

// The reference of the kernels that test against the zero region: its copy, k-d tree and boundary
// marks (ZeroSet), rebuilt at reset and kept in step with removals.
class ZeroSetKernel {
 public:
  explicit ZeroSetKernel(const CollisionParams& params) : params_(params) {}

  // Copies the zero rows and builds their tree; marks the boundary surfels when params.boundary.
  void reset(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows, int threads);
  void on_removed(const std::vector<bool>& keep, const IndexList& new_row) { zero_.on_removed(keep, new_row); }
  void on_inserted(Index /*added*/) {}
  void bind(const CollisionScene& /*scene*/) {}  // the references are copies
  const ZeroSet* zero_set() const { return &zero_; }
  std::size_t memory_bytes() const { return zero_.memory_bytes(); }
  // Snapshots (collision_snapshot.cpp): the references as they are (trees rebuilt from the same points in the
  // same order, which gives the same tree); load() checks them against `rows` model rows.
  bool snapshottable() const { return true; }
  void save(SnapshotWriter& out) const;
  void load(SnapshotReader& in, Index rows);

 protected:
  // The §4.1 test of a point against its nearest zero surfel k (`previous_state`: before the step).
  SimpleTest test(Index k, const TestPoint& pt, bool previous_state, bool bounded = true) const {
    return simple_test(params_, zero_, k, pt.p, pt.radius(), pt.previous(), previous_state, bounded);
  }

  // The deformable rows' nearest zero surfels as zero_.tree->knn(their positions, 1) answers them (#deformable by 1),
  // kept by reset() from the boundary marks, which ask for them (ZeroSet::mark_boundary), for the seed that follows
  // (Temporal); moved out by the first call, else (no marks, other rows) that batch made afresh.
  KnnResult reset_nearest(const Points& queries, int threads) const {
    KnnResult out = std::move(reset_nearest_);
    reset_nearest_ = KnnResult();
    return out.indices.rows() == queries.rows() && out.indices.cols() == 1 ? out : zero_.tree->knn(queries, 1, threads);
  }

  CollisionParams params_;
  ZeroSet zero_;
  bool zero_cells_ = false;          // build zero_'s tree with cells when exact (ZeroSet::cells; Simple, Temporal)
  bool keep_reset_nearest_ = false;  // reset() keeps the marks' nearest zero surfels for the seed (Temporal)
  mutable KnnResult reset_nearest_;  // what reset_nearest() hands out once: empty after it, or without marks
};

class SimpleKernel : public ZeroSetKernel {
 public:
  struct State {
    double depth = 0.0;     // |d| at the last test (model units)
    std::uint8_t hit = 0;   // colliding
    std::uint8_t unbounded = 0;  // 1: its next test ignores the step bound (the zero region moved near it)
    std::uint8_t pad[2] = {};    // no padding bytes: the undo journal compares states bytewise (Journal::note)
    std::uint32_t leaf = 0;      // the zero tree's leaf that held the last nearest: where the next query starts
                                 // (KdTree::nearest_from; exact queries only; a stale one costs time, not exactness)
    bool colliding() const { return hit != 0; }
  };
  static_assert(sizeof(State) == 16, "State has padding bytes");
  static constexpr bool kSeeded = false;  // nothing to measure at reset
  static constexpr int kChunk = 256;

  // Every point queries every step, from its last winner's leaf when the queries are exact (the zero tree then keeps
  // cells, as Temporal's).
  explicit SimpleKernel(const CollisionParams& params) : ZeroSetKernel(params) { zero_cells_ = true; }

  void seed(const CollisionScene&, const IndexList&, const IndexList&, int, RowStates<State>&) const {}
  State init(const Vec3&, const NearestZero&) const { return {}; }
  double depth(const State& s, const Vec3&) const { return s.depth; }
  // One §4.1 test of s; returns it (Improved's sweep needs |d|^2).
  SimpleTest test(State& s, const TestPoint& pt) const {
    const SimpleTest t = ZeroSetKernel::test(zero_.nearest_from(pt.p, s.leaf), pt, s.colliding(), !s.unbounded);
    s.unbounded = 0;
    s.hit = t.state;
    s.depth = std::sqrt(t.dist2);
    return t;
  }
  Index update(State& s, const TestPoint& pt) const {
    test(s, pt);
    return 1;
  }
  // No zero surfel within the point's step: the step bound keeps its state and depth.
  Index not_candidate(State&, const TestPoint&) const { return 0; }
  void skip(State&, const TestPoint&) const {}
  State child(const State& parent, const Vec3&) const { return parent; }
  void keep_parent(State&, const Vec3&) const {}
  // Every point queries its nearest zero surfel every step: the zero copies are all there is to update.
  // The points the moved surfaces may have crossed are tested without the step bound next time.
  // The zero set's copies of the moved rows are where they were (`before` is not needed).
  bool on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& /*before*/,
                      const IndexList& deformable, RowStates<State>& states, int threads) {
    const double reach = zero_.move_rows(scene, rows);
    if (reach < 0.0) return false;
    for (Index r : rows_near_moved<false>(scene, rows, reach, deformable, states, threads)) states[r].unbounded = 1;
    return true;
  }
};

}  // namespace surfeledit::detail
