// Simple Algo (§4.1, Code 6.1) and Improved Simple Algo (§4.2, spatial coherence).
//
// Simple: every step, each deformable surfel queries its nearest zero surfel and is tested with the
// §4.1 heuristics (boundary marks, per-surfel step bound). Independent per surfel: multithreaded.
// Improved: the same test, but after testing s1 with distance |d| > sqrt(H) every not-yet-settled
// deformable surfel strictly inside B(p1, |d|) takes s1's state without a query. H is the mean |d|^2
// of the surfels tested in the previous step; H = 0 on the first step after a reset (propagate from
// every test). The result depends on the order (ascending rows), so Improved runs single-threaded.
//
// Depth of a colliding surfel: its distance |d| to the nearest zero surfel (a settled surfel at
// distance e from s1 gets |d| - e, a lower bound of its own |d|), so all four algorithms report the
// distance to the reference surface in the sense of Eq. 6.4.
#include <cmath>
#include <limits>

#include "collision_detail.hpp"

namespace surfeledit {

namespace {

using namespace detail;

class SimpleDetector final : public NarrowDetector {
 public:
  SimpleDetector(const CollisionParams& params, bool improved) : NarrowDetector(params), improved_(improved) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    ZeroSet zero;
    zero.build(scene, zero_rows, params_.knn_eps);
    if (params_.boundary) {
      zero.mark_boundary(scene, deformable, params_.boundary_n, params_.boundary_i, resolve_threads(params_.threads));
    }
    zero_ = std::move(zero);
    deformable_ = std::move(deformable);
    rows_ = static_cast<Index>(scene.regions.size());
    colliding_.assign(static_cast<std::size_t>(rows_), 0);
    depth_.assign(static_cast<std::size_t>(rows_), 0.0);
    mean_dist2_ = 0.0;  // first step: propagate from every test (Improved)
    preprocess_ms_ = ms_since(start);
  }

  // A row that is not a candidate keeps its state and depth (Simple only: Improved's spatial
  // coherence needs every query, so hierarchies refuse it).
  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* candidate) override {
    const auto start = std::chrono::steady_clock::now();
    require_scene_rows(scene, rows_, "detect");
    if (previous.rows() != rows_) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
    CollisionResult result;
    if (improved_) {
      if (candidate) throw Error(ErrorCode::Internal, "algorithm", "improved cannot run on candidates only");
      detect_improved(scene, previous, result.stats);
    } else {
      detect_simple(scene, previous, candidate, result.stats);
    }
    collect_result(
        result, deformable_, [&](std::size_t, Index r) { return colliding_[r] != 0; },
        [&](std::size_t, Index r) { return depth_[r]; }, preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
    const IndexList new_row = remap_rows(keep);
    zero_.on_removed(keep, new_row);
    deformable_ = remap_list(deformable_, keep, new_row);
    compact(colliding_, keep);
    compact(depth_, keep);
    rows_ = static_cast<Index>(colliding_.size());
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    const Index added = static_cast<Index>(parents.size());
    require_scene_rows(scene, rows_ + added, "on_inserted");
    require_deformable_parents(scene, rows_, parents);
    for (Index k = 0; k < added; ++k) {
      colliding_.push_back(colliding_[parents[k]]);
      depth_.push_back(depth_[parents[k]]);
      deformable_.push_back(rows_ + k);
    }
    rows_ += added;
  }

  std::size_t memory_bytes() const override {
    return zero_.memory_bytes() + deformable_.capacity() * sizeof(Index) + colliding_.capacity() +
           depth_.capacity() * sizeof(double);
  }

 private:
  void detect_simple(const CollisionScene& scene, const Points& previous, const std::vector<std::uint8_t>* candidate,
                     CollisionStats& stats) {
    const Index n = static_cast<Index>(deformable_.size());
    const int threads = resolve_threads(params_.threads);
    Index tested = 0;
    auto one = [&](Index q) -> Index {
      const Index r = deformable_[q];
      if (candidate && !(*candidate)[r]) return 0;
      const Vec3 p1 = row3(scene.positions, r);
      const Index k = zero_.nearest(p1);
      const SimpleTest t = simple_test(params_, zero_, k, p1, scene.radii[r], row3(previous, r), colliding_[r]);
      colliding_[r] = t.state;
      depth_[r] = std::sqrt(t.dist2);
      return 1;
    };
    if (threads == 1 || n < 2048) {
      for (Index q = 0; q < n; ++q) tested += one(q);
    } else {
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads) reduction(+ : tested)
      for (Index q = 0; q < n; ++q) tested += one(q);
    }
    stats.tested = tested;
    stats.queries = tested;
  }

  void detect_improved(const CollisionScene& scene, const Points& previous, CollisionStats& stats) {
    std::vector<std::uint8_t> settled(static_cast<std::size_t>(rows_), 0);
    std::unique_ptr<KdTree> moving;  // per-step tree over the deformable positions, built on first need
    IndexList hits;
    std::vector<double> hit_dist2;
    double sum_dist2 = 0.0;
    Index tested = 0, queries = 0;
    for (Index r : deformable_) {
      if (settled[r]) continue;
      const Vec3 p1 = row3(scene.positions, r);
      const Index k = zero_.nearest(p1);
      ++queries;
      const SimpleTest t = simple_test(params_, zero_, k, p1, scene.radii[r], row3(previous, r), colliding_[r]);
      colliding_[r] = t.state;
      depth_[r] = std::sqrt(t.dist2);
      settled[r] = 1;
      ++tested;
      sum_dist2 += t.dist2;
      if (!(t.dist2 > mean_dist2_)) continue;
      // No zero surfel lies strictly inside B(p1, |d|): every deformable surfel in it shares s1's state.
      if (!moving) moving = std::make_unique<KdTree>(scene.positions, deformable_);
      const double reach = std::sqrt(t.dist2);
      moving->radius(p1, reach * (1.0 + 1e-9) + 1e-300, hits, hit_dist2);
      for (Index j : hits) {
        if (settled[j]) continue;
        const double e2 = (row3(scene.positions, j) - p1).squaredNorm();
        if (!(e2 < t.dist2)) continue;  // strictly inside, measured in world coordinates
        settled[j] = 1;
        colliding_[j] = t.state;
        depth_[j] = reach - std::sqrt(e2);
      }
    }
    mean_dist2_ = tested > 0 ? sum_dist2 / tested : 0.0;
    stats.tested = tested;
    stats.queries = queries;
  }

  bool improved_;
  ZeroSet zero_;
  IndexList deformable_;                 // rows with region != Zero, ascending
  Index rows_ = 0;                       // rows of the model the state refers to
  std::vector<std::uint8_t> colliding_;  // per row
  std::vector<double> depth_;            // per row: depth estimate of the last evaluation
  double mean_dist2_ = 0.0;              // H: mean |d|^2 of the previous step's tested surfels
  double preprocess_ms_ = 0.0;
};

}  // namespace

namespace detail {
std::unique_ptr<NarrowDetector> make_simple_detector(const CollisionParams& params, bool improved) {
  return std::make_unique<SimpleDetector>(params, improved);
}
}  // namespace detail

}  // namespace surfeledit
