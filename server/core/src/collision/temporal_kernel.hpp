// Temporal Coherence Algo as a kernel (§4.3 of docs/algorithms.md, thesis §6.2): each point keeps a
// sphere (c, rho2) that holds no zero surfel; while the point stays strictly inside it its state
// cannot have changed and it is skipped. Otherwise it queries its nearest zero surfel, re-centres the
// sphere (c = p, rho2 from |d| and the sphere margin) and is tested with the §4.1 heuristics.
// Depth (Eq. 6.4): rho - |p - c| while skipped, |d| when tested.
// With `inside` = winding | vote (§4.6) the test is "inside the rigid solid" (InsideModel) instead of
// the §4.1 heuristics; with `swept` (§4.7) a point whose step passed through the solid collides in
// that step (and is re-tested at the next).
#pragma once

#include <algorithm>
#include <cmath>

#include "inside_model.hpp"
#include "simple_kernel.hpp"

namespace surfeledit::detail {

class TemporalKernel : public ZeroSetKernel {
 public:
  struct State {
    Sphere sphere;          // holds no zero surfel
    double depth = 0.0;     // depth estimate of the last evaluation (model units)
    std::uint8_t hit = 0;   // colliding (1: by the test, 2: only by the swept test this step)
    std::uint8_t unbounded = 0;  // 1: its next test ignores the step bound (the zero region moved near it)
    std::uint8_t pad[2] = {};    // no padding bytes: the undo journal compares states bytewise (Journal::note)
    std::uint32_t leaf = 0;      // the zero tree's leaf that held the last nearest: where the next query starts
                                 // (KdTree::nearest_from; exact queries only; a stale one costs time, not exactness)
    bool colliding() const { return hit != 0; }
  };
  static_assert(sizeof(State) == 48, "State has padding bytes");
  static constexpr bool kSeeded = true;
  static constexpr int kChunk = 512;

  // The zero tree keeps cells when the queries are exact (knn_eps == 0): each point's query starts at its last
  // winner's leaf (State::leaf; 28 B per tree node, RESULTS §63).
  explicit TemporalKernel(const CollisionParams& params) : ZeroSetKernel(params) {
    zero_cells_ = true;
    keep_reset_nearest_ = true;
  }

  void reset(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows, int threads) {
    ZeroSetKernel::reset(scene, deformable, zero_rows, threads);
    build_inside();
  }
  void on_removed(const std::vector<bool>& keep, const IndexList& new_row) {
    const KdTree* before = zero_.tree.get();
    ZeroSetKernel::on_removed(keep, new_row);
    if (zero_.tree.get() != before) build_inside();
  }
  std::size_t memory_bytes() const { return ZeroSetKernel::memory_bytes() + (inside_ ? inside_->memory_bytes() : 0); }
  // Snapshots: the zero set's (ZeroSetKernel); not with an inside model (winding, vote, swept).
  bool snapshottable() const { return !inside_; }

  void seed(const CollisionScene& scene, const IndexList& deformable, const IndexList&, int threads,
            RowStates<State>& states) const {
    seed_states(
        *this, scene.positions, deformable, [&](const Points& queries) { return reset_nearest(queries, threads); },
        zero_.positions, zero_.radii, states);
  }
  State init(const Vec3& p, const NearestZero& z) const {
    State s;
    s.sphere = {p, sphere_rho2(z.dist2, z.radius, params_.sphere_margin)};
    return s;
  }
  double depth(const State& s, const Vec3&) const { return s.depth; }
  Index update(State& s, const TestPoint& pt) const {
    const double moved2 = (pt.p - s.sphere.center).squaredNorm();
    if (moved2 < s.sphere.rho2) return stay(s, moved2);
    if (inside_) return update_inside(s, pt);
    return retest(s, pt, zero_.nearest_from(pt.p, s.leaf));
  }
  // Probes (kernel.hpp): the search of a test, found for a block of rows before their updates.
  struct Probe {
    Index near = -1;         // zero surfel nearest to the point (index into the zero copies)
    std::uint32_t leaf = 0;  // the leaf holding it (State::leaf's next value)
  };
  bool probing() const { return !inside_; }
  // update()'s search when the point left its sphere (true; the zero surfel found is being fetched), else false.
  [[gnu::always_inline]] bool probe(const State& s, const TestPoint& pt, Probe& found) const {
    if ((pt.p - s.sphere.center).squaredNorm() < s.sphere.rho2) return false;
    found.leaf = s.leaf;
    found.near = zero_.nearest_from(pt.p, found.leaf);
    const auto k = static_cast<std::ptrdiff_t>(found.near);
    __builtin_prefetch(zero_.positions.data() + 3 * k);
    __builtin_prefetch(zero_.positions.data() + 3 * k + 2);
    __builtin_prefetch(zero_.normals.data() + 3 * k);
    __builtin_prefetch(zero_.normals.data() + 3 * k + 2);
    __builtin_prefetch(zero_.radii.data() + k);
    return true;
  }
  // update() with what probe() found (null when it returned false: the point is inside its sphere).
  [[gnu::always_inline]] Index update(State& s, const TestPoint& pt, const Probe* found) const {
    if (!found) return stay(s, (pt.p - s.sphere.center).squaredNorm());
    s.leaf = found->leaf;
    return retest(s, pt, found->near);
  }
  // The sleeping blocks' sphere (kernel.hpp): inside it only a colliding point's depth changes (stay()).
  [[gnu::always_inline]] static const Sphere* quiet_sphere(const State& s) {
    return s.colliding() ? nullptr : &s.sphere;
  }
  // Unprobed, only a colliding point's depth changes (stay()).
  [[gnu::always_inline]] static bool keeps(const State& s) { return !s.colliding(); }
  static bool keeps_not_candidate(const State&, const TestPoint&) { return false; }  // it may be tested
  // A point that leaves its sphere needs its nearest zero distance for its next sphere whether or not
  // the broad phase ruled it out (the step bound then keeps its state): Temporal ignores candidates.
  Index not_candidate(State& s, const TestPoint& pt) const { return update(s, pt); }
  void skip(State&, const TestPoint&) const {}
  State child(const State& parent, const Vec3& p) const { return split_child(parent, p); }
  void keep_parent(State& parent, const Vec3& p) const { parent.sphere.keep_if_contains(p); }
  // The zero copies, then the points a moved surface may have crossed or whose sphere holds a moved
  // surfel: tested at their next step, without the step bound. Not with an inside model
  // (winding, vote, swept): a moved part changes the solid those test against everywhere near it.
  // The zero set's copies of the moved rows are where they were (`before` is not needed).
  bool on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& /*before*/,
                      const IndexList& deformable, RowStates<State>& states, int threads) {
    if (inside_) return false;
    const double reach = zero_.move_rows(scene, rows);
    if (reach < 0.0) return false;
    for (Index r : rows_near_moved<true>(scene, rows, reach, deformable, states, threads)) {
      states[r].sphere.rho2 = 0.0;
      states[r].unbounded = 1;
    }
    return true;
  }

 private:
  // A point strictly inside its sphere (at squared distance moved2 from its centre): its state stands, a colliding
  // one's depth estimate follows it.
  [[gnu::always_inline]] Index stay(State& s, double moved2) const {
    if (s.colliding()) s.depth = std::max(0.0, std::sqrt(s.sphere.rho2) - std::sqrt(moved2));
    return 0;
  }
  // The thesis's test of a point that left its sphere against zero surfel k, its nearest.
  Index retest(State& s, const TestPoint& pt, Index k) const {
    const SimpleTest t = test(k, pt, s.colliding(), !s.unbounded);
    s.unbounded = 0;
    s.sphere = {pt.p, sphere_rho2(t.dist2, zero_.radii[k], params_.sphere_margin)};
    s.hit = t.state;
    s.depth = std::sqrt(t.dist2);
    return 1;
  }
  // The model when `inside` is not nearest or `swept` is on (else null: the thesis's test).
  void build_inside() {
    inside_.reset();
    if (params_.inside == InsideMode::Nearest && !params_.swept) return;
    inside_ = std::make_shared<const InsideModel>(zero_.positions, zero_.normals, zero_.radii, zero_.tree, params_);
  }
  Index update_inside(State& s, const TestPoint& pt) const {
    const InsideModel::Probe pr = inside_->probe(pt.p);
    Index made = 1;
    const double r = inside_->radius(pr.nearest);
    s.sphere = {pt.p, inside_->sphere_rho2(pt.p, pr.dist2, r, params_.sphere_margin)};
    s.depth = std::sqrt(pr.dist2);
    if (params_.inside == InsideMode::Nearest) {  // swept only: the thesis's test, then the segment
      const SimpleTest t = test(pr.nearest, pt, s.colliding() && s.hit != 2);
      s.hit = t.state;
    } else {
      s.hit = pr.inside;
    }
    if (params_.swept && !s.hit && InsideModel::may_cross(pt.p - pt.previous(), r) &&
        inside_->crossed(pt.previous(), pt.p, made)) {
      s.hit = 2;
      s.sphere.rho2 = 0.0;  // tested again at the next step
    }
    return made;
  }

  std::shared_ptr<const InsideModel> inside_;
};

}  // namespace surfeledit::detail
