// Robust Algo as a kernel (§4.4 of docs/algorithms.md, thesis §6.3, Code 6.8): points are classified
// against the ORIGINAL whole model (taken at reset: zero surfels plus the deformable ones at their
// positions then, k-d tree built once). Only the deformable rows' values at reset are copied; the zero
// rows are read from the model (bind()), where they stay until another tool moves them
// (on_rigid_moved, which is told where they were). A change of that inside state counts as a
// collision change only when the nearest original surfel is a zero surfel; a point collides iff its
// state changed an odd number of times (Def. 4.3). Each point keeps a sphere (c, rho2) and is only
// re-tested once it leaves it. Depth (Eq. 6.4): rho - |p - c|.
// With `inside` = winding | vote (§4.6) the inside state is "inside the rigid solid" (InsideModel over
// the zero region) and every change of it counts; spheres then hold no zero surfel. With `swept`
// (§4.7) a point whose step passed through the solid is also reported in that step.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "inside_model.hpp"
#include "kernel.hpp"
#include "surfeledit/core/rank_bits.hpp"

namespace surfeledit::detail {

// The flags of a Robust state.
struct RobustFlags {
  static constexpr std::uint8_t kInside = 1;       // inside the original model at the last test
  static constexpr std::uint8_t kColliding = 2;    // odd number of counted changes
  static constexpr std::uint8_t kFirstUpdate = 4;  // inside state to be re-derived at the old position
  static constexpr std::uint8_t kCrossed = 8;      // swept: the last step passed through the solid
  static constexpr std::uint8_t kOldHeld = 16;     // RobustHeldState::old_position holds the old position
};

// A Robust state of a row detector's point (40 bytes; the row sweep reads every state every step and writes only
// those of the points it tests or that start or stop colliding, so that the undo journal notes only them). Its old
// position -- the last position at which it did not collide, where a forgotten inside state (kFirstUpdate) is
// re-derived -- is implicit: the point's position at its last update, which is where the next step's detection
// finds it before the step (TestPoint::previous(); between steps, its position now; after reset, where it was then).
// A point that collides never has its inside state forgotten, so its old position is never read.
struct RobustState {
  Sphere sphere;                // holds no original surfel
  std::uint8_t flags = 0;       // RobustFlags: kInside | kColliding | kFirstUpdate | kCrossed (| kOldHeld)
  std::uint8_t pad[3] = {};     // no padding bytes: the undo journal compares states bytewise (Journal::note)
  std::uint32_t leaf = 0;       // the original tree's leaf that held the last nearest: where the next test's search
                                // starts (KdTree::nearest_from; a stale one costs time, not exactness)
  bool colliding() const { return (flags & (RobustFlags::kColliding | RobustFlags::kCrossed)) != 0; }
};
static_assert(sizeof(RobustState) == 40, "RobustState has padding bytes");

// The simplified detector's Robust state: a point may also skip steps (its cluster inactive, skip()), and its
// old position -- its position before the first step it skipped -- is then held (kOldHeld) until its next update.
struct alignas(64) RobustHeldState : RobustState {
  Vec3 old_position = Vec3::Zero();  // the old position while kOldHeld is set (a stale value otherwise)
};
static_assert(sizeof(RobustHeldState) == 64, "RobustHeldState has padding bytes");

// kHeld: the states hold old positions (RobustHeldState; for a driver that calls skip()), else RobustState.
template <bool kHeld>
class RobustKernelT : public RobustFlags {
 public:
  using State = std::conditional_t<kHeld, RobustHeldState, RobustState>;
  static constexpr bool kSeeded = true;
  static constexpr bool kSeedApart = true;  // seed() builds its own tree over the zero rows and reads params_ only
  static constexpr int kChunk = 512;

  explicit RobustKernelT(const CollisionParams& params) : params_(params) {}

  // The model as it is now becomes the original model (its deformable rows copied, its tree built). Throws
  // InvalidArgument when there are no zero rows.
  void reset(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows, int threads);
  // Spheres start with the distance to the nearest zero surfel (a temporary tree over the zero rows).
  void seed(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows, int threads,
            RowStates<State>& states) const;
  State init(const Vec3& p, const NearestZero& z) const {
    State s;
    s.sphere = {p, sphere_rho2(z.dist2, z.radius, params_.sphere_margin)};
    s.flags = kFirstUpdate;  // its old position: p, where the next step finds it before moving it
    return s;
  }
  // rho - |p - c| (Eq. 6.4), p being where the point was at its update this step.
  double depth(const State& s, const Vec3& p) const {
    return std::max(0.0, std::sqrt(s.sphere.rho2) - (p - s.sphere.center).norm());
  }
  [[gnu::always_inline]] Index update(State& s, const TestPoint& pt) const {
    Index made = 0;
    if (leaves(s, pt)) made = test(s, pt.p, pt.previous());
    finish(s, pt);
    return made;
  }
  // Probes (kernel.hpp): the original model's searches of a test, found for a block of rows before their updates.
  struct Probe {
    Index near = -1;         // original row nearest to the point
    Index near_old = -1;     // original row nearest to the old position, when its inside state is re-derived; else -1
    std::uint32_t leaf = 0;  // the leaf holding `near` (State::leaf's next value)
  };
  bool probing() const { return !with_inside(); }
  // update()'s searches when the point left its sphere (true; the rows they found are being fetched), else false.
  [[gnu::always_inline]] bool probe(const State& s, const TestPoint& pt, Probe& found) const {
    if (!leaves(s, pt)) return false;
    found = search(s, pt);
    prefetch_ref(found.near);
    if (found.near_old >= 0) prefetch_ref(found.near_old);
    return true;
  }
  // update() with what probe() found (null when it returned false).
  [[gnu::always_inline]] Index update(State& s, const TestPoint& pt, const Probe* found) const {
    Index made = 0;
    if (found) {
      s.flags &= static_cast<std::uint8_t>(~kCrossed);
      double r_near;
      made = classify(s, pt.p, old(s, pt.prev), *found, r_near);
    }
    finish(s, pt);
    return made;
  }
  // Unprobed, only finish() may write: when it drops a held old position.
  [[gnu::always_inline]] static bool keeps(const State& s) { return !(s.flags & kOldHeld); }
  // The inside model's open-boundary balls (none without one); after bind(), which builds a pending one.
  std::vector<ZeroBall> open_boundary() const { return inside_ ? inside_->hole_balls() : std::vector<ZeroBall>{}; }
  // Not a candidate: nor is anything of not_candidate() written but finish()'s, once its sphere is empty and its
  // inside state forgotten (or while it collides, or stays in its sphere).
  [[gnu::always_inline]] static bool keeps_not_candidate(const State& s, const TestPoint& pt) {
    if ((s.flags & kCrossed) || !keeps(s)) return false;
    return (s.flags & kColliding) || ((s.flags & kFirstUpdate) && s.sphere.rho2 == 0.0) || !leaves(s, pt);
  }
  // The sleeping blocks' sphere (kernel.hpp): inside it update() and not_candidate() only call finish(), which keeps
  // the bytes of a state without a held old position; a colliding or crossed point has none.
  [[gnu::always_inline]] static const Sphere* quiet_sphere(const State& s) {
    return (s.flags & (kColliding | kCrossed | kOldHeld)) ? nullptr : &s.sphere;
  }
  // Whether the point at pt left its sphere (is tested this step).
  [[gnu::always_inline]] static bool leaves(const State& s, const TestPoint& pt) {
    return (pt.p - s.sphere.center).squaredNorm() >= s.sphere.rho2;
  }
  // Not a candidate: it keeps its collision state. If it left its sphere and does not collide, its
  // inside state is forgotten (re-derived at its previous position when it is tested next) and its
  // sphere emptied, so that it is tested as soon as it is a candidate again; a colliding one keeps
  // everything (it is still inside, farther than its step from the zero surface). An empty sphere stays where
  // it is: no point is inside it wherever its centre (Sphere::contains), and its state's bytes then do not
  // change from step to step while the point is not a candidate.
  // Nothing is stored that does not change: most rows of a step with a broad phase are not candidates, and a store
  // of the same value still makes the state's cache line one to write back.
  Index not_candidate(State& s, const TestPoint& pt) const {
    std::uint8_t flags = static_cast<std::uint8_t>(s.flags & ~kCrossed);
    if (leaves(s, pt) && !(flags & kColliding)) {
      flags |= kFirstUpdate;
      if (s.sphere.rho2 != 0.0) s.sphere = {pt.p, 0.0};
    }
    if (flags != s.flags) s.flags = flags;
    finish(s, pt);
    return 0;
  }
  // Its inside state may go stale while it is not tested, so its next test re-derives it from its old
  // position (the last position at which it was found not colliding), as after a reset: the parity then
  // compares that position with the new one, across the untested steps. The old position is held from
  // now on (the point's position before this step; it does not move with the steps it skips).
  // Only with states that hold old positions (RobustKernelT<true>).
  template <bool H = kHeld, std::enable_if_t<H, int> = 0>
  void skip(State& s, const TestPoint& pt) const {
    hold_old(s, pt.prev);
    s.flags = static_cast<std::uint8_t>((s.flags | kFirstUpdate) & ~kCrossed);
  }
  // Child: the parent's state (inside, colliding, first update, old position) and the sphere rule.
  State child(const State& parent, const Vec3& p) const { return split_child(parent, p); }
  void keep_parent(State& parent, const Vec3& p) const { parent.sphere.keep_if_contains(p); }

  // A removed zero surfel leaves the original model too (the rigid part no longer has it); removed
  // deformable surfels stay in it (they still describe the undeformed shape).
  void on_removed(const std::vector<bool>& keep, const IndexList& new_row);
  void on_inserted(Index added) {
    spell_out_rows();
    orig_of_row_.resize(orig_of_row_.size() + static_cast<std::size_t>(added), -1);
  }
  // Moved zero rows take their new place in the original model (the rigid part is where it is now; the
  // deformable part's original surfaces stay where they were at reset), the original model's tree is
  // rebuilt (a new object), and the points a moved surface may have crossed or whose sphere holds a moved
  // surfel (rows_near_moved) are tested at their next step. Inside states and parities are kept: that test
  // compares a point's inside state with the rigid part where it is now. `before`: where the moved rows
  // were (the old tree's points). Not with an inside model (winding, vote, swept).
  bool on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& before,
                      const IndexList& deformable, RowStates<State>& states, int threads);
  // Points into the model's arrays for this step's zero-row reads; builds the original model's tree when it
  // has none (after a removal of zero rows or a snapshot load: from the model as it is now, which is where
  // this detector's zero rows are while its tool is not stale).
  void bind(const CollisionScene& scene);
  const ZeroSet* zero_set() const { return nullptr; }
  // The deformable rows at reset (CollisionDetector::reset_rows): the original model's copy.
  CollisionDetector::ResetRows reset_rows() const { return {&orig_.positions, &orig_.normals}; }
  std::size_t memory_bytes() const;
  // Snapshots (collision_snapshot.cpp): the references as they are (trees rebuilt from the same points in the
  // same order, which gives the same tree); load() checks them against `rows` model rows.
  bool snapshottable() const { return !with_inside(); }  // not with an inside model (winding, vote, swept)
  void save(SnapshotWriter& out) const;
  void load(SnapshotReader& in, Index rows);

 private:
  // The original model (#O rows = rows at reset): its zero rows are the model's (row_of()), its deformable
  // rows copied at reset.
  struct Original {
    RankBits deformable;              // #O: deformable at reset; such a row's values are at its rank below
    Points positions;                 // #D by 3: the deformable rows at reset, in row order
    Points normals;                   // #D by 3
    Values radii;                     // #D
    std::vector<std::uint8_t> alive;  // #O: 0 once a zero surfel was removed from the model; empty while all are alive
    std::shared_ptr<const KdTree> tree;  // over the alive rows; immutable, shared by copies; null until bind() builds it
  };
  // One surfel of the original model, as a test reads it.
  struct Ref {
    Vec3 p;         // position
    Vec3 n;         // unit normal
    double radius;  // disc radius
    bool zero;      // a zero surfel (a change of inside state against it counts)
  };
  // Where original row o's values are: in the copy (deformable) or in the bound model (zero).
  struct At {
    const double* p;  // position (3)
    const double* n;  // normal (3)
    const double* r;  // radius
    bool zero;        // a zero surfel
  };
  [[gnu::always_inline]] At at(Index o) const {
    const bool deformable = orig_.deformable.test(o);
    // Its index in the copy or its model row (row_of(o) may be -1 for a removed deformable row: not picked then).
    const std::ptrdiff_t i = deformable ? orig_.deformable.rank(o) : row_of(o);
    return {(deformable ? orig_.positions.data() : model_positions_) + 3 * i,
            (deformable ? orig_.normals.data() : model_normals_) + 3 * i,
            (deformable ? orig_.radii.data() : model_radii_) + i, !deformable};
  }
  // Original row o.
  Ref ref(Index o) const {
    const At a = at(o);
    return {Vec3(a.p[0], a.p[1], a.p[2]), Vec3(a.n[0], a.n[1], a.n[2]), *a.r, a.zero};
  }
  // Asks for the cache lines ref(o) reads. Inlined: GCC takes an out-of-line function of prefetches alone for
  // one without effects and drops its calls (RESULTS §68).
  [[gnu::always_inline]] void prefetch_ref(Index o) const {
    const At a = at(o);
    __builtin_prefetch(a.p);
    __builtin_prefetch(a.p + 2);
    __builtin_prefetch(a.n);
    __builtin_prefetch(a.n + 2);
    __builtin_prefetch(a.r);
  }
  bool alive(Index o) const { return orig_.alive.empty() || orig_.alive[static_cast<std::size_t>(o)] != 0; }
  Index original_rows() const { return orig_.deformable.rows(); }
  // The original model's positions (#O by 3; removed rows 0), zero rows from `scene` but the rows `moved` at
  // `before` (the model before the move), when given.
  Points original_points(const CollisionScene& scene, const IndexList* moved = nullptr,
                         const RigidRows* before = nullptr) const;
  // The original model's k-d tree over its alive rows (every row while all are alive), as reset, removals,
  // rigid moves and snapshot loads build it; leaves of kNearestLeafSize points (collision_detail.hpp).
  std::shared_ptr<const KdTree> original_tree(const Points& positions);

  // Tests a point that left its sphere at p1: re-derives a forgotten inside state, counts a change
  // of it against a zero surfel, re-centres the sphere. Returns the queries made.
  // Out of line: most points of a step are not tested, and the sweep inlines update() around it.
  [[gnu::noinline]] Index test(State& s, const Vec3& p1, const Vec3& p0) const {
    s.flags &= static_cast<std::uint8_t>(~kCrossed);
    double r_near = 0.0;  // radius of the reference surfel nearest to p1
    const double* prev = p0.data();
    Index made = params_.inside == InsideMode::Nearest ? test_original(s, p1, prev, r_near)
                                                       : test_zero(s, p1, prev, r_near);
    if (params_.swept && !s.colliding()) {
      if (InsideModel::may_cross(p1 - p0, r_near) && inside_->crossed(p0, p1, made)) {
        s.flags |= kCrossed;
        s.sphere.rho2 = 0.0;  // tested again at the next step
      }
    }
    return made;
  }
  // The inside state against the rigid solid (InsideModel); every change counts.
  // `prev`: the point's position before the step (3 doubles).
  Index test_zero(State& s, const Vec3& p1, const double* prev, double& r_near) const {
    Index made = 0;
    if (s.flags & kFirstUpdate) {
      s.flags &= static_cast<std::uint8_t>(~kFirstUpdate);
      ++made;
      set_inside(s, inside_->probe(old(s, prev)).inside);
    }
    const InsideModel::Probe pr = inside_->probe(p1);
    ++made;
    r_near = inside_->radius(pr.nearest);
    s.sphere = {p1, inside_->sphere_rho2(p1, pr.dist2, r_near, params_.sphere_margin)};
    if (pr.inside != static_cast<bool>(s.flags & kInside)) s.flags ^= kColliding;
    set_inside(s, pr.inside);
    return made;
  }
  // The thesis's test against the original model (Code 6.8): its searches (search()), then what they found
  // (classify()).
  Index test_original(State& s, const Vec3& p1, const double* prev, double& r_near) const {
    const Vec3 p0 = old(s, prev);
    return classify(s, p1, p0, search(s, p1, p0), r_near);
  }
  // The searches of a test at p1: the original surfel nearest to p1, from the state's leaf, and the one nearest
  // to the old position p0 when a forgotten inside state (kFirstUpdate) is to be re-derived there. That is only when
  // the nearest to p1 is a zero surfel: against a deformable one no change counts, and the state is overwritten
  // by p1's, so that query cannot change the result (an exact skip: RESULTS §50). It starts from the leaf of p1's
  // winner (the old position is mostly the last step's position, one step from p1; 1.02x over the near-path
  // leaf, RESULTS §75).
  Probe search(const State& s, const Vec3& p1, const Vec3& p0) const {
    Probe f;
    f.leaf = s.leaf;
    f.near = orig_.tree->nearest_from(p1, f.leaf);
    if (!orig_.deformable.test(f.near) && (s.flags & kFirstUpdate) != 0) {
      std::uint32_t start = f.leaf;
      f.near_old = orig_.tree->nearest_from(p0, start);
    }
    return f;
  }
  Probe search(const State& s, const TestPoint& pt) const {
    // The old position is read only for a re-derivation (old() is cheap, and its value unused otherwise).
    return search(s, pt.p, old(s, pt.prev));
  }
  // The state after a test at p1 (old position p0) whose searches found `f`.
  Index classify(State& s, const Vec3& p1, const Vec3& p0, const Probe& f, double& r_near) const {
    const double w = params_.threshold;
    s.leaf = f.leaf;
    const Ref k = ref(f.near);
    Index made = 1;
    const Vec3 d = p1 - k.p;
    r_near = k.radius;
    s.sphere = {p1, sphere_rho2(d.squaredNorm(), k.radius, params_.sphere_margin)};
    const bool inside_now = d.dot(k.n) < w;
    if (f.near_old >= 0) {
      ++made;
      const Ref k0 = ref(f.near_old);
      set_inside(s, (p0 - k0.p).dot(k0.n) < w);
    }
    // Against a zero surfel a change of inside state flips the parity (by a select, not a branch on k.zero).
    const bool flip = k.zero & (inside_now != static_cast<bool>(s.flags & kInside));
    s.flags ^= static_cast<std::uint8_t>(flip ? kColliding : 0);
    s.flags &= static_cast<std::uint8_t>(~kFirstUpdate);
    set_inside(s, inside_now);
    return made;
  }
  // The inside model over the alive zero surfels, when `inside` or `swept` needs it.
  void build_inside();
  // The old position of a point whose position before this step is `prev` (3 doubles; between steps: its position
  // now).
  [[gnu::always_inline]] static Vec3 old(const State& s, const double* prev) {
    if constexpr (kHeld) {
      if (s.flags & kOldHeld) return s.old_position;
    }
    return Vec3(prev[0], prev[1], prev[2]);
  }
  // Holds the old position from now on (the implicit one, `prev` as in old()).
  static void hold_old(State& s, const double* prev) {
    if constexpr (kHeld) {
      if (s.flags & kOldHeld) return;
      s.old_position = Vec3(prev[0], prev[1], prev[2]);
      s.flags |= kOldHeld;
    }
  }
  // End of every update: the position of a point that does not collide is its last non-colliding one, implicit from
  // now on (the next step finds the point there before it); that of a point that collides is never read. A held
  // old position is dropped; otherwise the state's bytes stay as they are.
  [[gnu::always_inline]] static void finish(State& s, const TestPoint&) {
    if constexpr (kHeld) {
      if (s.flags & kOldHeld) s.flags &= static_cast<std::uint8_t>(~kOldHeld);
    } else {
      (void)s;
    }
  }
  static void set_inside(State& s, bool in) {
    s.flags = in ? (s.flags | kInside) : (s.flags & static_cast<std::uint8_t>(~kInside));
  }

  CollisionParams params_;
  Original orig_;
  // #P: row of the original model, -1 for inserted rows; empty while it is the identity (no row was
  // inserted or removed since the reset: 4 bytes per row saved).
  IndexList orig_of_row_;
  // #O: model row of an original row, -1 once removed; empty while it is the identity (no row removed since
  // the reset; insertions append rows, so they keep it).
  IndexList row_of_orig_;
  Index orig_of(Index r) const { return orig_of_row_.empty() ? r : orig_of_row_[static_cast<std::size_t>(r)]; }
  Index row_of(Index o) const { return row_of_orig_.empty() ? o : row_of_orig_[static_cast<std::size_t>(o)]; }
  std::size_t rows_now() const {
    return orig_of_row_.empty() ? static_cast<std::size_t>(original_rows()) : orig_of_row_.size();
  }
  // orig_of_row_ as a list (before rows are inserted or removed).
  void spell_out_rows() {
    if (!orig_of_row_.empty()) return;
    orig_of_row_.resize(static_cast<std::size_t>(original_rows()));
    for (std::size_t r = 0; r < orig_of_row_.size(); ++r) orig_of_row_[r] = static_cast<Index>(r);
  }
  // The model bound by bind(): #P by 3, #P by 3, #P (row-major).
  const double* model_positions_ = nullptr;
  const double* model_normals_ = nullptr;
  const double* model_radii_ = nullptr;
  void bind_model(const CollisionScene& scene);
  bool with_inside() const { return params_.inside != InsideMode::Nearest || params_.swept; }
  bool pending_inside_ = false;
  // Bytes of the original model's tree as last built: memory_bytes() counts it while the tree waits for the next
  // bind (after a removal or a snapshot load), so the history's byte counts do not depend on when it is built.
  std::size_t tree_bytes_ = 0;  // the inside model is to be built at the next bind (zero rows were removed)
  std::shared_ptr<const InsideModel> inside_;  // over the alive zero surfels; null with nearest and no swept
};

// The row detector's kernel (no skips: old positions implicit) and the simplified detector's.
using RobustKernel = RobustKernelT<false>;
using RobustHeldKernel = RobustKernelT<true>;
extern template class RobustKernelT<false>;
extern template class RobustKernelT<true>;

}  // namespace surfeledit::detail
