// The per-point kernel contract of the collision detectors (internal header).
//
// An algorithm (Simple §4.1, Temporal §4.3, Robust §4.4 of docs/algorithms.md; thesis ch. 6) is a
// *kernel*: the state one tested point carries from step to step, and what one step does to it. The
// row detector (row_detector.hpp) drives a kernel over the deformable rows of a model, behind a
// hierarchy's broad phase or not; the simplified detector (collision_simplified.cpp) drives the same
// kernel over its tested points (original surfels and cluster surfels). A kernel never loops over
// rows and never touches threads: it is called once per point, from any thread, concurrently for
// different points. The contract, as code (every kernel provides exactly this):
//
//   struct Kernel {
//     // Per tested point; a default-constructed State is "not colliding, empty sphere".
//     struct State {
//       bool colliding() const;  // colliding after the last evaluation
//     };
//     // Depth estimate (model units, >= 0) of a point colliding after this step's update, now at p.
//     double depth(const State& s, const Vec3& p) const;
//     static constexpr bool kSeeded;  // init() needs the nearest zero surfel of the point
//     static constexpr int kChunk;    // OpenMP dynamic chunk of the row loop (rows per task)
//
//     explicit Kernel(const CollisionParams& params);
//     // Builds the references (zero set, original model) from the model as it is now.
//     void reset(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows,
//                int threads);
//     // Row detector: the initial states of the deformable rows (`states` has #P entries).
//     void seed(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows,
//               int threads, RowStates<State>& states) const;
//     // Optional: true when seed() reads nothing reset() writes (it builds its own references from the scene and
//     // reads only the kernel's settings), so that a row driver with threads > 1 may run the two at once
//     // (KernelRows::build_seeded; Robust: the original model's tree beside the seed's tree and queries).
//     static constexpr bool kSeedApart;
//     // The state right after reset of a point at p whose nearest zero surfel is `zero`.
//     State init(const Vec3& p, const NearestZero& zero) const;
//     // One step for a tested point. Returns the nearest-neighbour queries made (> 0: it was tested).
//     Index update(State& s, const TestPoint& pt) const;
//     // One step for a point the broad phase ruled out (no zero surfel within its step). Returns
//     // the queries made.
//     Index not_candidate(State& s, const TestPoint& pt) const;
//     // A point not tested this step because its cluster is inactive (it keeps "not colliding").
//     void skip(State& s, const TestPoint& pt) const;
//     // The state of a child split from `parent`, the child at p (§4.4, thesis §6.5); then the
//     // parent's own state once it sits at p. Called through split_states() (children first).
//     State child(const State& parent, const Vec3& p) const;
//     void keep_parent(State& parent, const Vec3& p) const;
//     // Rows removed (`keep` per old row, `new_row` from remap_rows) / `added` rows appended.
//     void on_removed(const std::vector<bool>& keep, const IndexList& new_row);
//     void on_inserted(Index added);
//     // Zero rows `rows` (ascending) moved (CollisionDetector::on_rigid_moved): `before` holds what they were
//     // (one entry per row of `rows`). Updates the references for them and the states of `deformable` that
//     // depended on where they were; false, nothing changed, when the kernel cannot (the detector is then reset).
//     bool on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& before,
//                         const IndexList& deformable, RowStates<State>& states, int threads);
//     // The model of this step, before any update() / not_candidate() of it (the driver calls it at the top of
//     // every detection): a kernel that reads references from the model (Robust: its zero rows) keeps
//     // pointers into `scene` until the next bind(); the others do nothing.
//     void bind(const CollisionScene& scene);
//     // The zero region's copy with its k-d tree, when the kernel has one (nullptr otherwise).
//     const ZeroSet* zero_set() const;
//     // Optional: the deformable rows at reset, when the kernel keeps them unchanged until its next reset
//     // (CollisionDetector::reset_rows; Robust). The driver answers none for a kernel without it.
//     CollisionDetector::ResetRows reset_rows() const;
//     std::size_t memory_bytes() const;  // references only (states are counted by the driver)
//
//     // Optional probes, for a kernel whose test is searches and then reads of the rows they found (Robust,
//     // Temporal): the row sweep (parallel_sweep.hpp) then runs a block of rows in two passes, every search
//     // first, then the updates, so that the rows found are fetched while the next searches run. Rows the broad
//     // phase ruled out are not probed (not_candidate()).
//     struct Probe;           // what the searches of one row's test found
//     bool probing() const;   // whether these settings test by probes (else update(s, pt) is called)
//     // update()'s searches, when it will test the point (true); reads the state only.
//     bool probe(const State& s, const TestPoint& pt, Probe& found) const;
//     // update(s, pt) with what probe() found (nullptr: probe() returned false).
//     Index update(State& s, const TestPoint& pt, const Probe* found) const;
//     // Whether update(s, pt, nullptr) / not_candidate(s, pt) leave s's bytes as they are (the journal then takes
//     // no before-image; false is always safe; a checked build compares the bytes: parallel_sweep.hpp, kChecked).
//     bool keeps(const State& s) const;
//     bool keeps_not_candidate(const State& s, const TestPoint& pt) const;
//
//     // Optional, for the row sweep's sleeping blocks (parallel_sweep.hpp, SleepingBlocks): a sphere such that while
//     // the point stays strictly inside it, update() and not_candidate() change nothing of s and it does not
//     // collide; nullptr when there is none (it collides, or its next update may change it wherever it is).
//     static const Sphere* quiet_sphere(const State& s);
//   };
//
// What a tested point asks about inside/outside beyond the thesis's nearest-surfel test (`inside` =
// winding | vote) and the swept test (`swept`) are not kernels: Temporal and Robust share one
// immutable InsideModel (inside_model.hpp, §4.6-§4.7 of docs/algorithms.md), built in reset() and
// on_removed(), asked in update(); its spheres (sphere_rho2) also stay clear of the open boundary.
#pragma once

#include <algorithm>
#include <vector>

#include "../collision_detail.hpp"
#include "surfeledit/core/rank_bits.hpp"

namespace surfeledit::detail {

// One tested point of a step: a deformable surfel or a cluster's simplified surfel. Radius and
// previous position are read through pointers, only by a point that is tested (most are skipped).
struct TestPoint {
  Vec3 p;                        // position now
  const double* r = nullptr;     // -> disc radius (model units)
  const double* prev = nullptr;  // -> position before the step (3 doubles, for the step bound)

  double radius() const { return *r; }
  Vec3 previous() const { return Vec3(prev[0], prev[1], prev[2]); }
};

// The TestPoints of a step's rows, from the arrays taken once for a sweep's loop: its states' stores (a one-byte
// flag may alias anything) would otherwise make the compiler read the arrays' data pointers again for every row.
struct StepRows {
  const double* positions;  // #P by 3, row-major
  const double* radii;      // #P
  const double* previous;   // #P by 3, row-major
  StepRows(const CollisionScene& scene, const Points& prev)
      : positions(scene.positions.data()), radii(scene.radii.data()), previous(prev.data()) {}
  [[gnu::always_inline]] TestPoint operator()(Index r) const {
    const double* p = positions + 3 * r;
    return {Vec3(p[0], p[1], p[2]), radii + r, previous + 3 * r};
  }
};

// The TestPoint of row r of a step (`previous`: #P by 3, row-major), for a loop that reads one row at a time.
inline TestPoint row_point(const CollisionScene& scene, const Points& previous, Index r) {
  return StepRows(scene, previous)(r);
}

// The zero surfel nearest to a point, as init() needs it.
struct NearestZero {
  double dist2 = 0.0;   // squared distance to it
  double radius = 0.0;  // its disc radius
};

// A temporal-coherence sphere (c, rho2): it holds no reference surfel, so a point strictly inside it
// keeps its state.
struct Sphere {
  Vec3 center = Vec3::Zero();  // c
  double rho2 = 0.0;           // squared radius; 0 = empty (the point is tested at its next step)

  bool contains(const Vec3& p) const { return (p - center).squaredNorm() < rho2; }
  // Keeps the sphere when it still contains p, else empties it at p.
  void keep_if_contains(const Vec3& p) {
    if (contains(p)) return;
    center = p;
    rho2 = 0.0;
  }
};

// One state per deformable row, indexed by model row (issue 14): which rows have a state is one bit per
// row with its rank (RankBits: 0.19 bytes per row against 4 for an int32 row -> slot map, RESULTS §47), and
// rows without one (zero rows) are never indexed. States are kept in ascending row order, so a sweep over the
// deformable rows walks them in storage order (stored_data()) and the state of row r is the rank(r)-th.
template <typename State>
class RowStates {
 public:
  // `rows` model rows; the rows `with_state` (ascending) get a default State.
  void assign(Index rows, const IndexList& with_state) {
    has_.assign(rows, with_state);
    dense_.assign(with_state.size(), State());
  }
  template <typename I>
  State& operator[](I r) { return dense_[static_cast<std::size_t>(has_.rank(static_cast<Index>(r)))]; }
  template <typename I>
  const State& operator[](I r) const { return dense_[static_cast<std::size_t>(has_.rank(static_cast<Index>(r)))]; }
  // Model rows (with or without a state).
  std::size_t size() const { return static_cast<std::size_t>(has_.rows()); }
  // Appends a row with state `s` (after every row that has one).
  void push_back(const State& s) {
    has_.push_back(true);
    dense_.push_back(s);
  }
  // Keeps the rows with keep[r] (one flag per row), in order.
  void compact(const std::vector<bool>& keep) {
    std::size_t d = 0;
    for (Index r = 0; r < has_.rows(); ++r) {
      if (!has_.test(r)) continue;
      const std::size_t s = static_cast<std::size_t>(has_.rank(r));
      if (keep[static_cast<std::size_t>(r)]) dense_[d++] = dense_[s];  // s >= d: states are in row order
    }
    dense_.resize(d);
    has_.compact(keep);
  }
  std::size_t memory_bytes() const { return has_.memory_bytes() + dense_.capacity() * sizeof(State); }

  // The states in storage order (ascending row): stored_data()[q] is the q-th row with a state.
  std::size_t stored() const { return dense_.size(); }
  State* stored_data() { return dense_.data(); }
  const State* stored_data() const { return dense_.data(); }
  // For snapshots (row_detector.hpp put_states / get_states): each row's slot (-1 without a state), and the states.
  std::vector<Index> slots() const {
    std::vector<Index> out(size(), -1);
    for (Index r = 0; r < has_.rows(); ++r)
      if (has_.test(r)) out[static_cast<std::size_t>(r)] = has_.rank(r);
    return out;
  }
  const std::vector<State>& dense() const { return dense_; }
  // Adopts `slots` and `dense` as read from a snapshot; the caller has checked that the slots >= 0 are
  // 0, 1, ... in row order and that there are dense.size() of them.
  void adopt(const std::vector<Index>& slots, std::vector<State> dense) {
    IndexList with;
    for (std::size_t r = 0; r < slots.size(); ++r)
      if (slots[r] >= 0) with.push_back(static_cast<Index>(r));
    has_.assign(static_cast<Index>(slots.size()), with);
    dense_ = std::move(dense);
  }

 private:
  RankBits has_;              // #P: rows with a state
  std::vector<State> dense_;  // one per row with a state, in ascending row order
};

// The initial states of `rows` (ascending) at their positions (Kernel::init), from each one's nearest zero surfel:
// `nearest(queries)` answers the rows' positions (#Q by 3) as KdTree::knn(queries, 1) does, with indices into
// `near_positions` (#N by 3) and `near_radii` (#N), never -1. One batch (along a Morton curve, each query warm-started
// from the previous answer, on the caller's threads): a seed's points are mostly far from the zero surface, where a
// cold single search meets many leaves (RESULTS §73). An exact tree answers as its single queries do, whatever the
// order and the threads.
template <typename Kernel, typename Nearest, typename States>
void seed_states(const Kernel& kernel, const Points& positions, const IndexList& rows, Nearest&& nearest,
                 const Points& near_positions, const Values& near_radii, States& states) {
  const Index n = static_cast<Index>(rows.size());
  Points queries(n, 3);
  for (Index q = 0; q < n; ++q) queries.row(q) = positions.row(rows[static_cast<std::size_t>(q)]);
  const KnnResult found = nearest(static_cast<const Points&>(queries));
  for (Index q = 0; q < n; ++q) {
    const Index r = rows[static_cast<std::size_t>(q)];
    const Vec3 p = row3(positions, r);
    const Index k = found.indices(q, 0);
    states[r] = kernel.init(p, NearestZero{(p - row3(near_positions, k)).squaredNorm(), near_radii[k]});
  }
}
// The same from the nearest point of `tree` (not empty, over the zero surfels), on `threads`.
template <typename Kernel, typename States>
void seed_states(const Kernel& kernel, const Points& positions, const IndexList& rows, int threads, const KdTree& tree,
                 const Points& near_positions, const Values& near_radii, States& states) {
  seed_states(
      kernel, positions, rows, [&](const Points& queries) { return tree.knn(queries, 1, threads); }, near_positions,
      near_radii, states);
}

// The NearestZero of p in `zero`.
inline NearestZero nearest_zero(const ZeroSet& zero, const Vec3& p) {
  const Index k = zero.nearest(p);
  return {(p - row3(zero.positions, k)).squaredNorm(), zero.radii[k]};
}

// The rows of `deformable` (ascending, as given) whose state a rigid move of the rows `moved` may have
// changed: a surface that swept across a point during a move of at most `reach` (the largest displacement
// of a moved surfel) ends within `reach` of it, so every point within reach + the radii of a moved surfel
// (at its position in `scene` now) is selected; with `kSphere`, also every point whose sphere now holds
// (strictly) a moved surfel. The others keep their states: no surface crossed them, and their spheres
// still hold no reference surfel.
template <bool kSphere, typename States>
IndexList rows_near_moved(const CollisionScene& scene, const IndexList& moved, double reach, const IndexList& deformable,
                          const States& states, int threads) {
  IndexList out;
  if (moved.empty()) return out;
  const KdTree near(scene.positions, moved);
  double r_max = 0.0;
  for (Index r : moved) r_max = std::max(r_max, scene.radii[r]);
  const Index n = static_cast<Index>(deformable.size());
  std::vector<std::uint8_t> hit(deformable.size(), 0);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (Index q = 0; q < n; ++q) {
    const Index r = deformable[q];
    const Vec3 p = row3(scene.positions, r);
    const double d = reach + r_max + scene.radii[r];
    if (near.nearest_within(p, d * d * (1.0 + 1e-9)) >= 0) {
      hit[q] = 1;
      continue;
    }
    if constexpr (kSphere) {
      const Sphere& sphere = states[r].sphere;
      if (!(sphere.rho2 > 0.0)) continue;
      // Widened for the tree's local-frame rounding; contains() decides in world coordinates.
      const Index k = near.nearest_within(sphere.center, sphere.rho2 * (1.0 + 1e-9));
      hit[q] = k >= 0 && sphere.contains(row3(scene.positions, k));
    }
  }
  for (std::size_t q = 0; q < hit.size(); ++q)
    if (hit[q]) out.push_back(deformable[q]);
  return out;
}

// Appends the states of split surfels: rows first_child + k were split from parents[k] (all children
// first, from their parent's state before the split; then the parents).
template <typename Kernel, typename States>
void split_states(const Kernel& kernel, const Points& positions, const IndexList& parents, States& states) {
  const Index first_child = static_cast<Index>(states.size());
  for (std::size_t k = 0; k < parents.size(); ++k)
    states.push_back(kernel.child(states[parents[k]], row3(positions, first_child + static_cast<Index>(k))));
  for (Index q : parents) kernel.keep_parent(states[q], row3(positions, q));
}

// Sphere-carrying kernels split alike: a child inside its parent's sphere takes the parent's state,
// sphere included; otherwise the parent's state with an empty sphere at the child. The parent keeps
// its sphere only while it lies inside it.
template <typename State>
State split_child(const State& parent, const Vec3& p) {
  State child = parent;
  child.sphere.keep_if_contains(p);
  return child;
}

}  // namespace surfeledit::detail
