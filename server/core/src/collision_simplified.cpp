// Approximate collision detection on the simplified deformable region (thesis §9.3; see
// simplify/approximate_detector.hpp). The per-surfel updates below are the exact detectors' own
// (collision_simple.cpp, collision_temporal.cpp, collision_robust.cpp), applied to one "tested point":
// either an original deformable surfel or a cluster's simplified surfel, each with its own state.
#include <algorithm>
#include <cmath>

#include "collision_detail.hpp"
#include "surfeledit/core/simplify/approximate_detector.hpp"
#include "surfeledit/core/simplify/clustering.hpp"

namespace surfeledit {

namespace {

using namespace detail;

constexpr std::uint8_t kInside = 1;       // Robust: inside the original model at the last test
constexpr std::uint8_t kColliding = 2;    // colliding (Robust: odd number of counted changes)
constexpr std::uint8_t kFirstUpdate = 4;  // Robust: inside state to be re-derived from old_position

// State of one tested point for the configured algorithm.
struct PointState {
  Vec3 center = Vec3::Zero();        // Temporal/Robust: temporal-coherence sphere centre c
  double rho2 = 0.0;                 // its squared radius
  Vec3 old_position = Vec3::Zero();  // Robust: last position at which the point did not collide
  double depth = 0.0;                // depth estimate of the last evaluation (model units)
  std::uint8_t flags = 0;            // kInside | kColliding | kFirstUpdate
  bool colliding() const { return flags & kColliding; }
};

class SimplifiedDetector final : public ApproximateDetector {
 public:
  SimplifiedDetector(const CollisionParams& params, const SimplifyParams& simplify)
      : ApproximateDetector(params), simplify_(simplify) {}

  const SimplifyParams& simplify_params() const override { return simplify_; }
  const ClusterMap& clusters() const override { return clusters_; }
  const ApproximateStats& approx_stats() const override { return approx_; }

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    const Index rows = static_cast<Index>(scene.regions.size());
    const int threads = resolve_threads(params_.threads);
    ZeroSet zero;
    zero.build(scene, zero_rows, params_.knn_eps);
    const bool robust = params_.algorithm == CollisionAlgorithm::Robust;
    if (!robust && params_.boundary) {
      zero.mark_boundary(scene, deformable, params_.boundary_n, params_.boundary_i, threads);
    }
    Snapshot orig;
    IndexList orig_of_row;
    if (robust) {
      orig.positions = scene.positions;
      orig.normals = scene.normals;
      orig.radii = scene.radii;
      orig.zero.resize(static_cast<std::size_t>(rows));
      for (Index r = 0; r < rows; ++r) orig.zero[r] = scene.regions[r] == Region::Zero;
      orig.alive.assign(static_cast<std::size_t>(rows), 1);
      orig.tree = std::make_unique<KdTree>(orig.positions, nearest_tree_params(params_.knn_eps));
      orig_of_row.resize(static_cast<std::size_t>(rows));
      for (Index r = 0; r < rows; ++r) orig_of_row[r] = r;
    }
    // Per-row states: spheres start with the distance to the nearest zero surfel.
    std::vector<PointState> state(static_cast<std::size_t>(rows));
    const Index n = static_cast<Index>(deformable.size());
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Index q = 0; q < n; ++q) {
      const Index r = deformable[q];
      state[r] = initial_state(zero, row3(scene.positions, r));
    }
    // Clusters of the deformable rows and their simplified surfels' states.
    const auto cluster_start = std::chrono::steady_clock::now();
    SimplifyParams sp = simplify_;
    sp.threads = params_.threads;
    ClusterMap map(rows, make_clusters(scene.positions, deformable, sp));
    approx_ = ApproximateStats{};
    approx_.simplify_ms = ms_since(cluster_start);
    const Index nc = map.cluster_count();
    std::vector<PointState> cstate(static_cast<std::size_t>(nc));
    std::vector<ProximityState> prox(static_cast<std::size_t>(nc));
#pragma omp parallel for schedule(static) num_threads(threads)
    for (Index c = 0; c < nc; ++c) {
      const IndexList& m = map.members(c);
      if (m.size() < 2) continue;
      cstate[c] = initial_state(zero, centroid(scene.positions, m));
    }
    zero_ = std::move(zero);
    orig_ = std::move(orig);
    orig_of_row_ = std::move(orig_of_row);
    deformable_ = std::move(deformable);
    rows_ = rows;
    state_ = std::move(state);
    clusters_ = std::move(map);
    cluster_state_ = std::move(cstate);
    prox_ = std::move(prox);
    preprocess_ms_ = ms_since(start);
  }

  CollisionResult detect(const CollisionScene& scene, const Points& previous) override {
    const auto start = std::chrono::steady_clock::now();
    require_scene_rows(scene, rows_, "detect");
    if (previous.rows() != rows_) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
    const int threads = resolve_threads(params_.threads);
    const Index nc = clusters_.cluster_count();
    // What one cluster's evaluation adds to the step's statistics (summed per thread, then merged).
    struct Counts {
      Index tested = 0, queries = 0, cluster_queries = 0, clusters = 0, singletons = 0, colliding_clusters = 0,
            near_clusters = 0, active_clusters = 0;
      void add(const Counts& o) {
        tested += o.tested;
        queries += o.queries;
        cluster_queries += o.cluster_queries;
        clusters += o.clusters;
        singletons += o.singletons;
        colliding_clusters += o.colliding_clusters;
        near_clusters += o.near_clusters;
        active_clusters += o.active_clusters;
      }
    };
    const double margin = simplify_.member_margin;
    const bool exact_members = simplify_.cluster_size == 1 || simplify_.method == SimplifyMethod::None;
    auto one = [&](Index c, Counts& n) {
      const IndexList& m = clusters_.members(c);
      if (m.empty()) return;
      ++n.clusters;
      // A one-surfel cluster is its own simplified surfel; with cluster_size 1 (or no simplification)
      // a surfel shares its cluster only with the surfels split from it, and all are tested.
      bool active = m.size() == 1 || exact_members;
      if (active) {
        ++n.singletons;
      } else {
        // The simplified surfel moved with its cluster: centroid of the members' current positions, a
        // radius covering their discs, and the previous centroid for the step bound.
        const Vec3 pc = centroid(scene.positions, m), prev = centroid(previous, m);
        double radius = 0.0;
        for (Index r : m) radius = std::max(radius, (row3(scene.positions, r) - pc).norm() + scene.radii[r]);
        PointState& cs = cluster_state_[c];
        n.cluster_queries += update(cs, pc, radius, prev);
        if (cs.colliding()) {
          ++n.colliding_clusters;
          active = true;
        }
        if (!active && margin > 0.0) {
          // Lower bound of the simplified surfel's distance to the zero region from the last query.
          ProximityState& ps = prox_[c];
          const double reach = margin * radius;
          if (ps.dist - (pc - ps.center).norm() <= reach) {
            const Index k = zero_.nearest(pc);
            ++n.cluster_queries;
            ps.center = pc;
            ps.dist = (pc - row3(zero_.positions, k)).norm();
            if (ps.dist <= reach) {
              ++n.near_clusters;
              active = true;
            }
          }
        }
        if (!active) {
          for (Index r : m) {
            if (state_[r].colliding()) {  // memorised: still colliding while its cluster does not
              active = true;
              break;
            }
          }
        }
      }
      if (active) {
        ++n.active_clusters;
        for (Index r : m) {
          const Index made = update(state_[r], row3(scene.positions, r), scene.radii[r], row3(previous, r));
          n.queries += made;
          n.tested += made > 0;
        }
      } else {
        for (Index r : m) skip(state_[r]);
      }
    };
    Counts total;
    if (threads == 1 || nc < 256) {
      for (Index c = 0; c < nc; ++c) one(c, total);
    } else {
#pragma omp parallel num_threads(threads)
      {
        Counts mine;
#pragma omp for schedule(dynamic, 64)
        for (Index c = 0; c < nc; ++c) one(c, mine);
#pragma omp critical(surfeledit_simplified_counts)
        total.add(mine);
      }
    }
    CollisionResult result;
    const double simplify_ms = approx_.simplify_ms;
    approx_ = ApproximateStats{total.clusters,      total.singletons,      total.colliding_clusters, total.near_clusters,
                               total.active_clusters, total.cluster_queries, simplify_ms};
    result.stats.tested = total.tested;
    result.stats.queries = total.queries + total.cluster_queries;
    collect_result(
        result, deformable_, [&](std::size_t, Index r) { return state_[r].colliding(); },
        [&](std::size_t, Index r) { return state_[r].depth; }, preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
    const IndexList new_row = remap_rows(keep);
    if (params_.algorithm == CollisionAlgorithm::Robust) {
      // As the exact Robust detector: removed zero surfels leave the original model.
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
      compact(orig_of_row_, keep);
    }
    zero_.on_removed(keep, new_row);
    deformable_ = remap_list(deformable_, keep, new_row);
    compact(state_, keep);
    clusters_.on_removed(keep);
    rows_ = static_cast<Index>(state_.size());
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    const Index added = static_cast<Index>(parents.size());
    require_scene_rows(scene, rows_ + added, "on_inserted");
    require_deformable_parents(scene, rows_, parents);
    const bool spheres = params_.algorithm != CollisionAlgorithm::Simple;
    for (Index k = 0; k < added; ++k) {
      const Index q = parents[k], b = rows_ + k;
      // Child B: the parent's state; its sphere if it lies inside it, else an empty one.
      PointState child = state_[q];
      const Vec3 pb = row3(scene.positions, b);
      if (spheres && !((pb - child.center).squaredNorm() < child.rho2)) {
        child.center = pb;
        child.rho2 = 0.0;
      }
      state_.push_back(child);
      deformable_.push_back(b);
      if (params_.algorithm == CollisionAlgorithm::Robust) orig_of_row_.push_back(-1);
    }
    // Child A (the parent row) keeps its sphere only if it lies inside it.
    if (spheres) {
      for (Index q : parents) {
        const Vec3 pa = row3(scene.positions, q);
        PointState& s = state_[q];
        if (!((pa - s.center).squaredNorm() < s.rho2)) {
          s.center = pa;
          s.rho2 = 0.0;
        }
      }
    }
    clusters_.on_inserted(parents);  // children join their parent's cluster
    rows_ += added;
  }

  // The clusters (members and row -> cluster map, cluster states) apart from the exact algorithm's state.
  std::size_t cluster_bytes() const {
    std::size_t members = 0;
    for (Index c = 0; c < clusters_.cluster_count(); ++c) members += clusters_.members(c).capacity() * sizeof(Index);
    return members + static_cast<std::size_t>(clusters_.rows()) * sizeof(Index) +
           cluster_state_.capacity() * sizeof(PointState);
  }

  std::vector<std::pair<std::string, std::size_t>> structures() const override {
    const std::size_t clusters = cluster_bytes();
    return {{std::string("collision_") + to_string(params_.algorithm), memory_bytes() - clusters},
            {std::string("clusters_") + to_string(simplify_.method), clusters}};
  }

  std::size_t memory_bytes() const override {
    std::size_t members = 0;
    for (Index c = 0; c < clusters_.cluster_count(); ++c) members += clusters_.members(c).capacity() * sizeof(Index);
    return zero_.memory_bytes() +
           static_cast<std::size_t>(orig_.positions.size() + orig_.normals.size() + orig_.radii.size()) * sizeof(double) +
           orig_.zero.capacity() + orig_.alive.capacity() + (orig_.tree ? orig_.tree->memory_bytes() : 0) +
           (orig_of_row_.capacity() + deformable_.capacity()) * sizeof(Index) +
           (state_.capacity() + cluster_state_.capacity()) * sizeof(PointState) +
           prox_.capacity() * sizeof(ProximityState) + members + static_cast<std::size_t>(clusters_.rows()) * sizeof(Index);
  }

 private:
  // The original model for Robust, frozen at reset (as in collision_robust.cpp).
  struct Snapshot {
    Points positions;                 // #O by 3
    Points normals;                   // #O by 3
    Values radii;                     // #O
    std::vector<std::uint8_t> zero;   // #O: 1 = zero surfel
    std::vector<std::uint8_t> alive;  // #O: 0 once a zero surfel was removed
    std::unique_ptr<KdTree> tree;     // over the alive rows
  };
  // Distance of a simplified surfel to the zero region at its last proximity query.
  struct ProximityState {
    Vec3 center = Vec3::Zero();  // where it was measured
    double dist = 0.0;           // distance to the nearest zero surfel there, model units (0 = measure now)
  };

  static Vec3 centroid(const Points& positions, const IndexList& rows) {
    Vec3 sum = Vec3::Zero();
    for (Index r : rows) sum += row3(positions, r);
    return sum / static_cast<double>(rows.size());
  }

  // State right after reset for a point at p: sphere from the nearest zero surfel, nothing collides.
  PointState initial_state(const ZeroSet& zero, const Vec3& p) const {
    PointState s;
    s.center = p;
    s.old_position = p;
    s.flags = kFirstUpdate;
    const Index k = zero.nearest(p);
    s.rho2 = sphere_rho2((p - row3(zero.positions, k)).squaredNorm(), zero.radii[k], params_.sphere_margin);
    return s;
  }

  // One step of the exact algorithm for one point (position p1, disc radius r1, position before the
  // step `prev`). Returns the nearest-neighbour queries made.
  Index update(PointState& s, const Vec3& p1, double r1, const Vec3& prev) const {
    switch (params_.algorithm) {
      case CollisionAlgorithm::Simple: {
        const Index k = zero_.nearest(p1);
        const SimpleTest t = simple_test(params_, zero_, k, p1, r1, prev, s.colliding());
        set_colliding(s, t.state);
        s.depth = std::sqrt(t.dist2);
        return 1;
      }
      case CollisionAlgorithm::Temporal: {
        const double moved2 = (p1 - s.center).squaredNorm();
        if (moved2 < s.rho2) {
          if (s.colliding()) s.depth = std::max(0.0, std::sqrt(s.rho2) - std::sqrt(moved2));
          return 0;
        }
        const Index k = zero_.nearest(p1);
        const SimpleTest t = simple_test(params_, zero_, k, p1, r1, prev, s.colliding());
        s.center = p1;
        s.rho2 = sphere_rho2(t.dist2, zero_.radii[k], params_.sphere_margin);
        set_colliding(s, t.state);
        s.depth = std::sqrt(t.dist2);
        return 1;
      }
      case CollisionAlgorithm::Robust: {
        Index made = 0;
        const double w = params_.threshold;
        if ((p1 - s.center).squaredNorm() >= s.rho2) {
          if (s.flags & kFirstUpdate) {
            s.flags &= static_cast<std::uint8_t>(~kFirstUpdate);
            const Index k = orig_.tree->nearest(s.old_position);
            ++made;
            const bool in = (s.old_position - row3(orig_.positions, k)).dot(row3(orig_.normals, k)) < w;
            set_flag(s, kInside, in);
          }
          const Index k = orig_.tree->nearest(p1);
          ++made;
          const Vec3 d = p1 - row3(orig_.positions, k);
          s.center = p1;
          s.rho2 = sphere_rho2(d.squaredNorm(), orig_.radii[k], params_.sphere_margin);
          const bool inside_now = d.dot(row3(orig_.normals, k)) < w;
          if (orig_.zero[k] && inside_now != static_cast<bool>(s.flags & kInside)) s.flags ^= kColliding;
          set_flag(s, kInside, inside_now);
        }
        if (s.colliding()) {
          s.depth = std::max(0.0, std::sqrt(s.rho2) - (p1 - s.center).norm());
        } else {
          s.old_position = p1;
        }
        return made;
      }
      default: break;
    }
    throw Error(ErrorCode::Internal, "algorithm", "not supported by the approximate detector");
  }

  // A member of a cluster that is not tested this step: it keeps "not colliding". Robust: its inside
  // state may go stale while it is not tested, so its next test re-derives it from old_position, the
  // last position at which it was tested and found not colliding (as at the first test after a reset);
  // the parity then compares that position with the new one, across the untested steps.
  void skip(PointState& s) const {
    if (params_.algorithm == CollisionAlgorithm::Robust) s.flags |= kFirstUpdate;
  }

  static void set_flag(PointState& s, std::uint8_t flag, bool on) {
    s.flags = on ? (s.flags | flag) : (s.flags & static_cast<std::uint8_t>(~flag));
  }
  static void set_colliding(PointState& s, bool on) { set_flag(s, kColliding, on); }

  SimplifyParams simplify_;
  ZeroSet zero_;                              // zero region: tests (Simple/Temporal), proximity, initial spheres
  Snapshot orig_;                             // Robust only
  IndexList orig_of_row_;                     // Robust: #P row of the original model, -1 for inserted rows
  IndexList deformable_;                      // rows with region != Zero, ascending
  Index rows_ = 0;
  std::vector<PointState> state_;             // #P: per original surfel (zero rows unused)
  ClusterMap clusters_;                       // deformable rows -> cluster
  std::vector<PointState> cluster_state_;     // #C: per simplified surfel (one-surfel clusters unused)
  std::vector<ProximityState> prox_;          // #C
  ApproximateStats approx_;
  double preprocess_ms_ = 0.0;
};

}  // namespace

std::unique_ptr<ApproximateDetector> make_approximate_detector(const CollisionParams& params,
                                                               const SimplifyParams& simplify) {
  validate(params);
  validate(simplify);
  switch (params.algorithm) {
    case CollisionAlgorithm::None: return nullptr;
    case CollisionAlgorithm::Improved:
      throw Error(ErrorCode::InvalidArgument, "algorithm",
                  "approximate detection supports simple, temporal and robust (improved is order-dependent)");
    default: break;
  }
  return std::make_unique<SimplifiedDetector>(params, simplify);
}

}  // namespace surfeledit
