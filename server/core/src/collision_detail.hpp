// Internal pieces shared by the collision detectors (not a public header). The per-point kernels and
// the detector that drives them over rows live in collision/ (kernel.hpp, row_detector.hpp).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit::detail {

// A detector whose per-surfel test can be limited to candidate rows: the narrow phase of the
// hierarchies (bvh/hierarchical_detector.hpp) runs the very same code as the detector without a hierarchy.
// A ball of the zero region's open boundary (an inside model's hole, collision/inside_model.hpp): across the cap that
// spans it the inside state of `inside` = winding | vote and the swept test changes far from every zero surfel.
struct ZeroBall {
  Vec3 center;
  double radius = 0.0;
};

class NarrowDetector : public CollisionDetector {
 public:
  // The open boundary's balls of the zero region as the next detect_candidates() of `scene` sees it (its inside
  // model then bound: a removal of zero rows rebuilds it first); none without an inside model. A broad phase makes
  // every row whose ball reaches one a candidate (bvh/hierarchical_detector.hpp).
  virtual std::vector<ZeroBall> open_boundary(const CollisionScene& scene) {
    (void)scene;
    return {};
  }
  // detect() where only rows with candidate[r] != 0 are tested (`candidate`: one flag per row;
  // nullptr = every row). The other deformable rows keep their collision state; what happens to
  // their spheres is each kernel's not_candidate() (collision/kernel.hpp).
  virtual CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                            const std::vector<std::uint8_t>* candidate) = 0;
  CollisionResult detect(const CollisionScene& scene, const Points& previous) override {
    return detect_candidates(scene, previous, nullptr);
  }
  CollisionResult detect_only(const CollisionScene& scene, const Points& previous,
                              const std::vector<std::uint8_t>& candidate) override {
    return detect_candidates(scene, previous, &candidate);  // the row detector re-tests only the candidates
  }

 protected:
  using CollisionDetector::CollisionDetector;
};

// Defined in collision.cpp: the row detector (collision/row_detector.hpp) of `params.algorithm`'s kernel
// (not None).
std::unique_ptr<NarrowDetector> make_narrow_detector(const CollisionParams& params);
// Defined in bvh/hierarchical_detector.cpp: `narrow` behind the broad phase of `hierarchy` (validated by the caller).
std::unique_ptr<CollisionDetector> make_hierarchical_detector(const CollisionParams& params,
                                                              const HierarchyParams& hierarchy,
                                                              std::unique_ptr<NarrowDetector> narrow);

inline Vec3 row3(const Points& a, Index i) { return a.row(i).transpose(); }

// Checks that every array of `scene` has `rows` rows (Internal otherwise: the session keeps them in step).
void require_scene_rows(const CollisionScene& scene, Index rows, const char* what);

// Rows of `scene` with region != Zero, ascending; `zero` gets the others.
void split_rows(const CollisionScene& scene, IndexList& deformable, IndexList& zero);

// The rows of `rows` that survive a removal, renumbered (`keep`, `new_row` as from remap_rows).
IndexList remap_list(const IndexList& rows, const std::vector<bool>& keep, const IndexList& new_row);

// Checks the rows appended after `rows` existing ones: each split from a deformable parent row and
// deformable itself; InvalidArgument ("parents") otherwise.
void require_deformable_parents(const CollisionScene& scene, Index rows, const IndexList& parents);

// Parameters of a detector's nearest-surfel tree: approximate search eps (0 = exact), and a turned frame for a scene
// tilted as a whole (KdTreeParams::align: on the tilted piercing scene Simple's step 390 -> 12.7 ms, Robust's and
// Temporal's 2.2-2.4x faster; an upright scene keeps the world axes and its bits; RESULTS §74).
inline KdTreeParams nearest_tree_params(double eps) {
  KdTreeParams p;
  p.eps = eps;
  p.align = true;
  return p;
}

// Leaves of the k-d trees the detectors ask for each point's one nearest surfel, exactly, from a leaf
// (KdTree::nearest_from: Simple's and Temporal's zero trees, Robust's original model). Measured on the piercing scene
// upright and tilted (bench_robust_step's BM_DetectRun and BM_DetectRunTilted): before the trees were turned (RESULTS §73, against
// 48) 128 points 0.97-1.02x upright and 1.16-1.47x tilted, where a far point's search met many loose axis-aligned
// leaf boxes; with the turned frame (§74) the tilted scene searches as the upright one, and 96 is 1.02-1.04x faster
// than 128 upright and 1.02-1.10x tilted, 64 0.96-1.04x. (Earlier, upright only: 48 1.23x the default 10, §63; with
// the AVX2 scan 48 over 24 and 32, §49.)
inline constexpr int kNearestLeafSize = 96;
// Leaves of Robust's seed tree (one batch of nearest queries at each reset, mostly far from the zero surface): 96
// makes the tilted reset 0.82x as fast as 128 (34 -> 42 ms), 64 0.84x (RESULTS §74).
inline constexpr int kSeedLeafSize = 128;

// The zero region as the Simple / Improved / Temporal detectors see it: a private copy of the zero
// surfels (they do not move), their k-d tree and their boundary marks (§4.1).
struct ZeroSet {
  Points positions;                  // #Z by 3
  Points normals;                    // #Z by 3
  Values radii;                      // #Z
  std::vector<std::uint8_t> marked;  // #Z: 1 = boundary surfel
  IndexList rows;                    // #Z: row in the model
  std::shared_ptr<const KdTree> tree;  // over `positions`; immutable once built, shared by copies
  double knn_eps = 0.0;              // approximate search of `tree` (CollisionParams::knn_eps)
  bool cells = false;                // `tree` keeps cells (KdTree::nearest_from) when knn_eps == 0 (Simple, Temporal)

  // Copies the zero rows of `scene` and builds the tree (approximate search `eps`; with cells when
  // `with_cells` and eps == 0). Throws InvalidArgument when there are none.
  void build(const CollisionScene& scene, const IndexList& zero_rows, double eps, bool with_cells = false);
  // The parameters `tree` is built with (eps; cells and kNearestLeafSize when `cells` and exact).
  KdTreeParams tree_params() const {
    KdTreeParams p = nearest_tree_params(knn_eps);
    p.cells = cells && knn_eps == 0.0;
    if (p.cells) p.leaf_size = kNearestLeafSize;
    p.frames = p.cells;
    return p;
  }
  // The parameters of the whole model's tree the boundary marks search (mark_boundary's `whole`).
  static KdTreeParams whole_tree_params(int threads) {
    KdTreeParams p = nearest_tree_params(0.0);
    p.threads = threads;
    return p;
  }
  // Boundary marks from the model as it is now: for each deformable row its `n` nearest other
  // surfels of the whole model (`whole`: its tree over scene.positions, whole_tree_params); the `i` nearest zero
  // surfels among them are marked.
  // `nearest` (optional): gets each deformable row's nearest zero surfel, as tree->knn(their positions, 1) answers
  // (#deformable by 1, indices into the copies), which the marks ask for anyway (a seeded kernel's seed needs it too).
  void mark_boundary(const CollisionScene& scene, const IndexList& deformable, const KdTree& whole, int n, int i,
                     int threads, KnnResult* nearest = nullptr);
  // The rows of `deformable` (ascending) that may have a zero surfel among their k nearest points of `whole` (the
  // whole model's tree): all but those with k points strictly closer than their nearest zero surfel. `nearest`
  // (optional) gets those nearest zero surfels (tree->knn(the rows' positions, 1)).
  IndexList rows_near_zero(const CollisionScene& scene, const IndexList& deformable, const KdTree& whole, int k,
                           int threads, KnnResult* nearest = nullptr) const;
  // Rows `moved` (model rows) moved: their copies take `scene`'s values, the tree is rebuilt (a new
  // object), the boundary marks are kept. Returns the largest displacement of a moved surfel (model
  // units), or -1 (nothing changed) when one of them is not in `rows`.
  double move_rows(const CollisionScene& scene, const IndexList& moved);
  // Index (into the copies) of the zero surfel nearest to p; -1 when there is none.
  Index nearest(const Vec3& p) const { return tree->nearest(p); }
  // The same, the search starting from `leaf` (the last winner's; updated) when the tree has cells; with
  // knn_eps > 0 the approximate nearest(p), `leaf` unchanged (KdTree::nearest_from).
  Index nearest_from(const Vec3& p, std::uint32_t& leaf) const { return tree->nearest_from(p, leaf); }
  // Drops removed rows (marks of the survivors are kept) and renumbers rows; rebuilds the tree
  // when a zero surfel went away.
  void on_removed(const std::vector<bool>& keep, const IndexList& new_row);
  std::size_t memory_bytes() const;
};

// The stats of collect_result / collect_hits.
inline void finish_result(CollisionResult& result, const IndexList& deformable, double preprocess_ms,
                          std::chrono::steady_clock::time_point start) {
  result.stats.deformable = static_cast<Index>(deformable.size());
  result.stats.colliding = static_cast<Index>(result.colliding.size());
  result.stats.preprocess_ms = preprocess_ms;
  result.stats.detect_ms = ms_since(start);
}

// The end of every detector's detect(): appends the colliding deformable rows (ascending, as
// `deformable` is) with their depth estimates and fills the stats all detectors report alike.
// `colliding(q, r)` and `depth(q, r)` receive the position q in `deformable` and the row r.
template <typename Colliding, typename Depth>
void collect_result(CollisionResult& result, const IndexList& deformable, Colliding colliding, Depth depth,
                    double preprocess_ms, std::chrono::steady_clock::time_point start) {
  for (std::size_t q = 0; q < deformable.size(); ++q) {
    const Index r = deformable[q];
    if (!colliding(q, r)) continue;
    result.colliding.push_back(r);
    result.depths.push_back(depth(q, r));
  }
  finish_result(result, deformable, preprocess_ms, start);
}
// The same from one flag per position of `deformable` (`hit`, 0 / 1), skipping 8 clear flags at a time:
// most steps find few colliding rows (RESULTS §39: the byte loop was a fifth of an idle step).
template <typename Depth>
void collect_hits(CollisionResult& result, const IndexList& deformable, const std::vector<std::uint8_t>& hit,
                  Depth depth, double preprocess_ms, std::chrono::steady_clock::time_point start) {
  const std::size_t n = deformable.size();
  const std::uint8_t* h = hit.data();
  for (std::size_t w = 0; w < n; w += 8) {
    if (w + 8 <= n) {
      std::uint64_t word;
      std::memcpy(&word, h + w, sizeof(word));
      if (word == 0) continue;
    }
    for (std::size_t q = w; q < std::min(n, w + 8); ++q) {
      if (!h[q]) continue;
      result.colliding.push_back(deformable[q]);
      result.depths.push_back(depth(q, deformable[q]));
    }
  }
  finish_result(result, deformable, preprocess_ms, start);
}

// scene.displacement_bound (CollisionScene) when the step carries one: refused before anything changes when it is
// negative or not finite (InvalidArgument naming it). The row sweeps and the hierarchies read it alike.
inline std::optional<double> checked_displacement_bound(const CollisionScene& scene) {
  if (scene.displacement_bound && !(*scene.displacement_bound >= 0.0 && std::isfinite(*scene.displacement_bound))) {
    throw Error(ErrorCode::InvalidArgument, "displacement_bound",
                "must be finite and >= 0, got " + std::to_string(*scene.displacement_bound));
  }
  return scene.displacement_bound;
}

// Squared radius of a temporal-coherence sphere around a point at squared distance `dist2` from its
// nearest reference surfel of radius `radius`: (|d| - margin * radius)^2, or 0 when that is not
// positive (the surfel is then re-tested at the next step). With margin 1 the sphere cannot reach
// into the nearest surfel's disc, so it does not poke through the sampled surface.
inline double sphere_rho2(double dist2, double radius, double margin) {
  if (margin == 0.0) return dist2;  // the thesis's sphere, bit for bit
  const double rho = std::sqrt(dist2) - margin * radius;
  return rho > 0.0 ? rho * rho : 0.0;
}

// One evaluation of the §4.1 test for deformable surfel s1 at p1 against zero surfel k.
struct SimpleTest {
  double dist2 = 0.0;  // |p1 - p2|^2
  bool state = false;  // colliding after the test
};
// `bounded` false: no step bound this time (the zero region moved near the point since its last test).
SimpleTest simple_test(const CollisionParams& params, const ZeroSet& zero, Index k, const Vec3& p1, double r1,
                       const Vec3& previous, bool previous_state, bool bounded = true);

}  // namespace surfeledit::detail
