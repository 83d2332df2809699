// Temporal Coherence Algo (§4.3, thesis §6.2): each deformable surfel keeps a sphere (c, rho2) that
// holds no zero surfel; while the surfel stays strictly inside it (|p - c|^2 < rho2) its state cannot
// have changed and it is skipped. Otherwise it queries its nearest zero surfel, re-centres the sphere
// (c = p, rho2 = |d|^2) and is tested with the §4.1 heuristics. Independent per surfel: multithreaded.
// Depth (Eq. 6.4): rho - |p - c|.
#include <algorithm>
#include <cmath>

#include "collision_detail.hpp"

namespace surfeledit {

namespace {

using namespace detail;

class TemporalDetector final : public NarrowDetector {
 public:
  explicit TemporalDetector(const CollisionParams& params) : NarrowDetector(params) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    ZeroSet zero;
    zero.build(scene, zero_rows, params_.knn_eps);
    const int threads = resolve_threads(params_.threads);
    if (params_.boundary) zero.mark_boundary(scene, deformable, params_.boundary_n, params_.boundary_i, threads);
    const Index rows = static_cast<Index>(scene.regions.size());
    center_ = scene.positions;
    rho2_.setZero(rows);
    const Index n = static_cast<Index>(deformable.size());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Index q = 0; q < n; ++q) {
      const Index r = deformable[q];
      const Vec3 p = row3(scene.positions, r);
      const Index k = zero.nearest(p);
      rho2_[r] = sphere_rho2((p - row3(zero.positions, k)).squaredNorm(), zero.radii[k], params_.sphere_margin);
    }
    zero_ = std::move(zero);
    deformable_ = std::move(deformable);
    rows_ = rows;
    colliding_.assign(static_cast<std::size_t>(rows_), 0);
    preprocess_ms_ = ms_since(start);
  }

  // `candidate` is not used: a surfel that leaves its sphere needs the distance to its nearest zero
  // surfel for its next sphere whether or not a broad phase could tell that its state is unchanged
  // (the step bound then keeps it), so behind a hierarchy Temporal does exactly what it does alone.
  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* /*candidate*/) override {
    const auto start = std::chrono::steady_clock::now();
    require_scene_rows(scene, rows_, "detect");
    if (previous.rows() != rows_) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
    const Index n = static_cast<Index>(deformable_.size());
    const int threads = resolve_threads(params_.threads);
    std::vector<double> depth(static_cast<std::size_t>(n), 0.0);
    Index tested = 0;
    auto one = [&](Index q) -> Index {
      const Index r = deformable_[q];
      const Vec3 p1 = row3(scene.positions, r);
      const double moved2 = (p1 - row3(center_, r)).squaredNorm();
      if (moved2 < rho2_[r]) {
        if (colliding_[r]) depth[q] = std::max(0.0, std::sqrt(rho2_[r]) - std::sqrt(moved2));
        return 0;
      }
      const Index k = zero_.nearest(p1);
      const SimpleTest t = simple_test(params_, zero_, k, p1, scene.radii[r], row3(previous, r), colliding_[r]);
      center_.row(r) = p1.transpose();
      rho2_[r] = sphere_rho2(t.dist2, zero_.radii[k], params_.sphere_margin);
      colliding_[r] = t.state;
      depth[q] = std::sqrt(t.dist2);
      return 1;
    };
    if (threads == 1 || n < 2048) {
      for (Index q = 0; q < n; ++q) tested += one(q);
    } else {
#pragma omp parallel for schedule(dynamic, 512) num_threads(threads) reduction(+ : tested)
      for (Index q = 0; q < n; ++q) tested += one(q);
    }
    CollisionResult result;
    result.stats.tested = tested;
    result.stats.queries = tested;
    collect_result(
        result, deformable_, [&](std::size_t, Index r) { return colliding_[r] != 0; },
        [&](std::size_t q, Index) { return depth[q]; }, preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
    const IndexList new_row = remap_rows(keep);
    // Removing zero surfels only empties spheres further: they stay valid.
    zero_.on_removed(keep, new_row);
    deformable_ = remap_list(deformable_, keep, new_row);
    compact(center_, keep);
    compact(rho2_, keep);
    compact(colliding_, keep);
    rows_ = static_cast<Index>(colliding_.size());
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    const Index added = static_cast<Index>(parents.size());
    require_scene_rows(scene, rows_ + added, "on_inserted");
    require_deformable_parents(scene, rows_, parents);
    center_.conservativeResize(rows_ + added, 3);
    rho2_.conservativeResize(rows_ + added);
    for (Index k = 0; k < added; ++k) {
      const Index q = parents[k], b = rows_ + k;
      colliding_.push_back(colliding_[q]);
      deformable_.push_back(b);
    }
    split_spheres(scene.positions, parents, rows_, center_, rho2_);
    rows_ += added;
  }

  std::size_t memory_bytes() const override {
    return zero_.memory_bytes() + deformable_.capacity() * sizeof(Index) + colliding_.capacity() +
           static_cast<std::size_t>(center_.size() + rho2_.size()) * sizeof(double);
  }

 private:
  ZeroSet zero_;
  IndexList deformable_;                 // rows with region != Zero, ascending
  Index rows_ = 0;
  Points center_;                        // #P by 3: sphere centres c (rows of zero surfels unused)
  Values rho2_;                          // #P: squared sphere radii
  std::vector<std::uint8_t> colliding_;  // #P
  double preprocess_ms_ = 0.0;
};

}  // namespace

namespace detail {
std::unique_ptr<NarrowDetector> make_temporal_detector(const CollisionParams& params) {
  return std::make_unique<TemporalDetector>(params);
}
}  // namespace detail

}  // namespace surfeledit
