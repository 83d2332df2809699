// Robust Algo (§4.4, thesis §6.3, Code 6.8), the default: deformable surfels are classified against
// the ORIGINAL whole model (a frozen snapshot taken at reset: zero surfels plus the deformable ones
// at their positions then, with its own copies of positions, normals and zero flags, k-d tree built
// once). A change of that inside state counts as a collision change only when the nearest original
// surfel is a zero surfel; a surfel collides iff its state changed an odd number of times (Def. 4.3).
// Each surfel keeps a sphere (c, rho2) and is only re-tested once it leaves it. Independent per
// surfel: multithreaded. Depth (Eq. 6.4): rho - |p - c|.
#include <algorithm>
#include <cmath>

#include "collision_detail.hpp"

namespace surfeledit {

namespace {

using namespace detail;

class RobustDetector final : public NarrowDetector {
 public:
  explicit RobustDetector(const CollisionParams& params) : NarrowDetector(params) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    if (zero_rows.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region is empty");
    const Index rows = static_cast<Index>(scene.regions.size());
    const int threads = resolve_threads(params_.threads);
    // The original model: every row as it is now.
    Snapshot orig;
    orig.positions = scene.positions;
    orig.normals = scene.normals;
    orig.radii = scene.radii;
    orig.zero.resize(static_cast<std::size_t>(rows));
    for (Index r = 0; r < rows; ++r) orig.zero[r] = scene.regions[r] == Region::Zero;
    orig.alive.assign(static_cast<std::size_t>(rows), 1);
    orig.tree = std::make_unique<KdTree>(orig.positions, nearest_tree_params(params_.knn_eps));
    IndexList orig_of_row(static_cast<std::size_t>(rows));
    for (Index r = 0; r < rows; ++r) orig_of_row[r] = r;
    // Spheres start with the distance to the nearest zero surfel (a temporary tree).
    const KdTree zero_tree(scene.positions, zero_rows, nearest_tree_params(params_.knn_eps));
    Values rho2 = Values::Zero(rows);
    const Index n = static_cast<Index>(deformable.size());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Index q = 0; q < n; ++q) {
      const Index r = deformable[q];
      const Vec3 p = row3(scene.positions, r);
      const Index k = zero_tree.nearest(p);
      rho2[r] = sphere_rho2((p - row3(scene.positions, k)).squaredNorm(), scene.radii[k], params_.sphere_margin);
    }
    orig_ = std::move(orig);
    orig_of_row_ = std::move(orig_of_row);
    deformable_ = std::move(deformable);
    rows_ = rows;
    center_ = scene.positions;
    old_position_ = scene.positions;
    rho2_ = std::move(rho2);
    flags_.assign(static_cast<std::size_t>(rows_), kFirstUpdate);
    preprocess_ms_ = ms_since(start);
  }

  // A row that is not a candidate keeps its collision state. If it left its sphere and does not
  // collide, its inside state is forgotten (first update: re-derived at its previous position when
  // it is tested next) and its sphere emptied, so that it is tested as soon as it is a candidate
  // again; a colliding one keeps everything (it is still inside, farther than its step from the
  // zero surface).
  CollisionResult detect_candidates(const CollisionScene& scene, const Points& previous,
                                    const std::vector<std::uint8_t>* candidate) override {
    const auto start = std::chrono::steady_clock::now();
    require_scene_rows(scene, rows_, "detect");
    if (previous.rows() != rows_) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
    const Index n = static_cast<Index>(deformable_.size());
    const int threads = resolve_threads(params_.threads);
    const double w = params_.threshold;
    std::vector<double> depth(static_cast<std::size_t>(n), 0.0);
    Index tested = 0, queries = 0;
    // Returns the number of nearest-neighbour queries made for deformable surfel q.
    auto one = [&](Index q) -> Index {
      const Index r = deformable_[q];
      const Vec3 p1 = row3(scene.positions, r);
      std::uint8_t& f = flags_[r];
      Index made = 0;
      const double moved2 = (p1 - row3(center_, r)).squaredNorm();
      if (moved2 >= rho2_[r] && candidate && !(*candidate)[r] && !(f & kColliding)) {
        f |= kFirstUpdate;
        center_.row(r) = p1.transpose();
        rho2_[r] = 0.0;
      } else if (moved2 >= rho2_[r] && (!candidate || (*candidate)[r])) {  // left its sphere
        if (f & kFirstUpdate) {
          f &= static_cast<std::uint8_t>(~kFirstUpdate);
          const Vec3 old = row3(old_position_, r);
          const Index k = orig_.tree->nearest(old);
          ++made;
          const bool in = (old - row3(orig_.positions, k)).dot(row3(orig_.normals, k)) < w;
          f = in ? (f | kInside) : (f & static_cast<std::uint8_t>(~kInside));
        }
        const Index k = orig_.tree->nearest(p1);
        ++made;
        const Vec3 d = p1 - row3(orig_.positions, k);
        center_.row(r) = p1.transpose();
        rho2_[r] = sphere_rho2(d.squaredNorm(), orig_.radii[k], params_.sphere_margin);
        const bool inside_now = d.dot(row3(orig_.normals, k)) < w;
        if (orig_.zero[k] && inside_now != static_cast<bool>(f & kInside)) f ^= kColliding;
        f = inside_now ? (f | kInside) : (f & static_cast<std::uint8_t>(~kInside));
      }
      if (f & kColliding) {
        const double moved = (p1 - row3(center_, r)).norm();
        depth[q] = std::max(0.0, std::sqrt(rho2_[r]) - moved);
      } else {
        old_position_.row(r) = p1.transpose();
      }
      return made;
    };
    if (threads == 1 || n < 2048) {
      for (Index q = 0; q < n; ++q) {
        const Index m = one(q);
        queries += m;
        tested += m > 0;
      }
    } else {
#pragma omp parallel for schedule(dynamic, 512) num_threads(threads) reduction(+ : tested, queries)
      for (Index q = 0; q < n; ++q) {
        const Index m = one(q);
        queries += m;
        tested += m > 0;
      }
    }
    CollisionResult result;
    result.stats.tested = tested;
    result.stats.queries = queries;
    collect_result(
        result, deformable_, [&](std::size_t, Index r) { return (flags_[r] & kColliding) != 0; },
        [&](std::size_t q, Index) { return depth[q]; }, preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
    const IndexList new_row = remap_rows(keep);
    // A removed zero surfel leaves the original model too (the rigid part no longer has it); removed
    // deformable surfels stay in it (they still describe the undeformed shape).
    bool zero_removed = false;
    for (Index r = 0; r < rows_; ++r) {
      const Index o = orig_of_row_[r];
      if (!keep[r] && o >= 0 && orig_.zero[o]) {
        orig_.alive[o] = 0;
        zero_removed = true;
      }
    }
    if (zero_removed) {
      IndexList alive;
      for (std::size_t o = 0; o < orig_.alive.size(); ++o)
        if (orig_.alive[o]) alive.push_back(static_cast<Index>(o));
      orig_.tree = std::make_unique<KdTree>(orig_.positions, alive, nearest_tree_params(params_.knn_eps));
    }
    deformable_ = remap_list(deformable_, keep, new_row);
    compact(orig_of_row_, keep);
    compact(center_, keep);
    compact(old_position_, keep);
    compact(rho2_, keep);
    compact(flags_, keep);
    rows_ = static_cast<Index>(flags_.size());
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    const Index added = static_cast<Index>(parents.size());
    require_scene_rows(scene, rows_ + added, "on_inserted");
    require_deformable_parents(scene, rows_, parents);
    const Index total = rows_ + added;
    center_.conservativeResize(total, 3);
    old_position_.conservativeResize(total, 3);
    rho2_.conservativeResize(total);
    for (Index k = 0; k < added; ++k) {
      const Index q = parents[k], b = rows_ + k;
      // Child B: the parent's state (inside, colliding, first update, old position); the spheres
      // follow split_spheres.
      flags_.push_back(flags_[q]);
      orig_of_row_.push_back(-1);
      deformable_.push_back(b);
      old_position_.row(b) = old_position_.row(q);
    }
    split_spheres(scene.positions, parents, rows_, center_, rho2_);
    rows_ = total;
  }

  std::size_t memory_bytes() const override {
    return static_cast<std::size_t>(orig_.positions.size() + orig_.normals.size() + orig_.radii.size()) * sizeof(double) +
           orig_.zero.capacity() + orig_.alive.capacity() + (orig_.tree ? orig_.tree->memory_bytes() : 0) +
           (orig_of_row_.capacity() + deformable_.capacity()) * sizeof(Index) +
           static_cast<std::size_t>(center_.size() + old_position_.size() + rho2_.size()) * sizeof(double) +
           flags_.capacity();
  }

 private:
  static constexpr std::uint8_t kInside = 1;       // inside the original model at the last test
  static constexpr std::uint8_t kColliding = 2;    // odd number of counted changes
  static constexpr std::uint8_t kFirstUpdate = 4;  // not yet tested since reset

  // The original model, frozen at reset (#O rows = rows at reset).
  struct Snapshot {
    Points positions;                  // #O by 3
    Points normals;                    // #O by 3
    Values radii;                      // #O
    std::vector<std::uint8_t> zero;    // #O: 1 = zero surfel
    std::vector<std::uint8_t> alive;   // #O: 0 once a zero surfel was removed from the model
    std::unique_ptr<KdTree> tree;      // over the alive rows of `positions`
  };

  Snapshot orig_;
  IndexList orig_of_row_;             // #P: row of the original model, -1 for inserted rows
  IndexList deformable_;              // rows with region != Zero, ascending
  Index rows_ = 0;
  Points center_;                     // #P by 3: sphere centres c
  Points old_position_;               // #P by 3: last position at which the surfel did not collide
  Values rho2_;                       // #P: squared sphere radii
  std::vector<std::uint8_t> flags_;   // #P: kInside | kColliding | kFirstUpdate
  double preprocess_ms_ = 0.0;
};

}  // namespace

namespace detail {
std::unique_ptr<NarrowDetector> make_robust_detector(const CollisionParams& params) {
  return std::make_unique<RobustDetector>(params);
}
}  // namespace detail

}  // namespace surfeledit
