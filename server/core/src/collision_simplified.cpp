// Approximate collision detection on the simplified deformable region (thesis §9.3; see
// simplify/approximate_detector.hpp): the clustering and which points are tested. The per-point
// updates are the exact detectors' kernels (collision/kernel.hpp), applied to one "tested point":
// either an original deformable surfel or a cluster's simplified surfel, each with its own state.
#include <algorithm>
#include <cmath>
#include <optional>

#include "at_once.hpp"
#include "collision/kernel_rows.hpp"
#include "collision/robust_kernel.hpp"
#include "collision/temporal_kernel.hpp"
#include "share_chunks.hpp"
#include "surfeledit/core/simplify/approximate_detector.hpp"
#include "surfeledit/core/simplify/clustering.hpp"

namespace surfeledit {

namespace {

using namespace detail;

template <typename Kernel>
class SimplifiedDetector final : public ApproximateDetector {
 public:
  using State = typename Kernel::State;

  SimplifiedDetector(const CollisionParams& params, const SimplifyParams& simplify)
      : ApproximateDetector(params), simplify_(simplify), rows_(params) {}

  const SimplifyParams& simplify_params() const override { return simplify_; }
  const ClusterMap& clusters() const override { return clusters_; }
  const ApproximateStats& approx_stats() const override { return approx_; }

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    const Index rows = static_cast<Index>(scene.regions.size());
    const int threads = resolve_threads(params_.threads);
    // The kernel's reset and seed, and the clusters of the deformable rows (which read only their positions): with
    // threads > 1 on a large model the two run at once, each on one thread (at_once.hpp), the same detector. Only for
    // region growing, which costs about as much as the kernel's part (piercing scene, one thread: ~50 ms against
    // 35-70); hierarchical clustering takes a few ms, and the kernel's part then loses more than that to running on
    // one thread (RESULTS §86.4).
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    const bool apart = simplify_.method == SimplifyMethod::RegionGrowing && !zero_rows.empty() &&
                       at_once_pays(threads, scene.regions.size());
    const int each = apart ? 1 : threads;
    std::optional<KernelRows<Kernel>> built;
    ZeroSet own_zero;  // the zero region for proximity and initial spheres when the kernel has none
    auto kernel_part = [&] {
      IndexList zero;
      built.emplace(KernelRows<Kernel>::build(params_, scene, each, zero));
      KernelRows<Kernel>& kr = *built;
      if (!kr.kernel.zero_set()) own_zero.build(scene, zero, params_.knn_eps);
      // Per-row states: spheres start with the distance to the nearest zero surfel.
      if (!Kernel::kSeeded) return;
      if (kr.kernel.zero_set()) {
        kr.kernel.seed(scene, kr.deformable, zero, each, kr.states);  // from that zero set
      } else {
        seed_states(kr.kernel, scene.positions, kr.deformable, each, *own_zero.tree, own_zero.positions, own_zero.radii,
                    kr.states);
      }
    };
    Clustering clustering;
    double simplify_ms = 0.0;
    auto cluster_part = [&] {
      const auto cluster_start = std::chrono::steady_clock::now();
      SimplifyParams sp = simplify_;
      sp.threads = each;
      clustering = make_clusters(scene.positions, deformable, sp);
      simplify_ms = ms_since(cluster_start);
    };
    at_once(apart, kernel_part, cluster_part);
    KernelRows<Kernel>& kr = *built;
    const Kernel& kernel = kr.kernel;
    const ZeroSet& zero = kernel.zero_set() ? *kernel.zero_set() : own_zero;
    auto nearest = [&](const Vec3& p) { return nearest_zero(zero, p); };
    // The simplified surfels' states.
    ClusterMap map(rows, clustering);
    approx_ = ApproximateStats{};
    approx_.simplify_ms = simplify_ms;
    const Index nc = map.cluster_count();
    std::vector<State> cstate(static_cast<std::size_t>(nc));
    std::vector<ProximityState> prox(static_cast<std::size_t>(nc));
    if (Kernel::kSeeded) {
#pragma omp parallel for schedule(static) num_threads(threads)
      for (Index c = 0; c < nc; ++c) {
        const IndexList& m = map.members(c);
        if (m.size() < 2) continue;
        const Vec3 p = centroid(scene.positions, m);
        cstate[c] = kernel.init(p, nearest(p));
      }
    }
    rows_ = std::move(kr);
    own_zero_ = std::move(own_zero);
    clusters_ = std::move(map);
    cluster_state_ = std::move(cstate);
    prox_ = std::move(prox);
    preprocess_ms_ = ms_since(start);
  }

  CollisionResult detect(const CollisionScene& scene, const Points& previous) override {
    const auto start = std::chrono::steady_clock::now();
    rows_.require_step(scene, previous);
    rows_.kernel.bind(scene);
    const int threads = resolve_threads(params_.threads);
    const Index nc = clusters_.cluster_count();
    const ZeroSet& zero = this->zero();
    const Kernel& kernel = rows_.kernel;
    RowStates<State>& state = rows_.states;
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
        State& cs = cluster_state_[c];
        n.cluster_queries += kernel.update(cs, TestPoint{pc, &radius, prev.data()});
        if (cs.colliding()) {
          ++n.colliding_clusters;
          active = true;
        }
        if (!active && margin > 0.0) {
          // Lower bound of the simplified surfel's distance to the zero region from the last query.
          ProximityState& ps = prox_[c];
          const double reach = margin * radius;
          if (ps.dist - (pc - ps.center).norm() <= reach) {
            const Index k = zero.nearest(pc);
            ++n.cluster_queries;
            ps.center = pc;
            ps.dist = (pc - row3(zero.positions, k)).norm();
            if (ps.dist <= reach) {
              ++n.near_clusters;
              active = true;
            }
          }
        }
        if (!active) {
          for (Index r : m) {
            if (state[r].colliding()) {  // memorised: still colliding while its cluster does not
              active = true;
              break;
            }
          }
        }
      }
      if (active) {
        ++n.active_clusters;
        for (Index r : m) {
          const Index made = kernel.update(state[r], row_point(scene, previous, r));
          n.queries += made;
          n.tested += made > 0;
        }
      } else {
        for (Index r : m) kernel.skip(state[r], row_point(scene, previous, r));
      }
    };
    Counts total;
    if (threads == 1 || nc < 256) {
      for (Index c = 0; c < nc; ++c) one(c, total);
    } else {
      // Chunks of 64 clusters shared without waiting for a descheduled helper (share_chunks.hpp); each chunk's
      // counts apart, summed in chunk order.
      constexpr Index kClustersPerChunk = 64;
      const Index chunks = (nc + kClustersPerChunk - 1) / kClustersPerChunk;
      std::vector<Counts> counts(static_cast<std::size_t>(chunks));
      share_chunks(threads, chunks, [&](Index k) {
        for (Index c = k * kClustersPerChunk; c < std::min(nc, (k + 1) * kClustersPerChunk); ++c)
          one(c, counts[static_cast<std::size_t>(k)]);
      });
      for (const Counts& c : counts) total.add(c);
    }
    CollisionResult result;
    const double simplify_ms = approx_.simplify_ms;
    approx_ = ApproximateStats{total.clusters,      total.singletons,      total.colliding_clusters, total.near_clusters,
                               total.active_clusters, total.cluster_queries, simplify_ms};
    result.stats.tested = total.tested;
    result.stats.queries = total.queries + total.cluster_queries;
    collect_result(
        result, rows_.deformable, [&](std::size_t, Index r) { return state[r].colliding(); },
        [&](std::size_t, Index r) { return kernel.depth(state[r], row3(scene.positions, r)); }, preprocess_ms_, start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    const IndexList new_row = rows_.on_removed(keep);
    if (!rows_.kernel.zero_set()) own_zero_.on_removed(keep, new_row);
    clusters_.on_removed(keep);
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    rows_.on_inserted(scene, parents);
    clusters_.on_inserted(parents);  // children join their parent's cluster
  }

  // The clusters (members and row -> cluster map, cluster states) apart from the exact algorithm's state.
  std::size_t cluster_bytes() const {
    std::size_t members = 0;
    for (Index c = 0; c < clusters_.cluster_count(); ++c) members += clusters_.members(c).capacity() * sizeof(Index);
    return members + static_cast<std::size_t>(clusters_.rows()) * sizeof(Index) +
           cluster_state_.capacity() * sizeof(State) + prox_.capacity() * sizeof(ProximityState);
  }

  std::vector<std::pair<std::string, std::size_t>> structures() const override {
    const std::size_t clusters = cluster_bytes();
    return {{std::string("collision_") + to_string(params_.algorithm), memory_bytes() - clusters},
            {std::string("clusters_") + to_string(simplify_.method), clusters}};
  }

  std::size_t memory_bytes() const override {
    return rows_.memory_bytes() + (rows_.kernel.zero_set() ? 0 : own_zero_.memory_bytes()) + cluster_bytes();
  }

  // Undo (history.hpp): a step changes the deformable rows' states, the simplified surfels' states and
  // proximities and the step's tallies; the clusters and the kernel's references change only at reset,
  // removal and insertion. detect() may re-test any member, so an image always holds every deformable row
  // (`rows` is ignored).
  std::shared_ptr<const DetectorImage> save_image(const IndexList*) const override {
    auto image = std::make_shared<Image>();
    image->states.reserve(rows_.deformable.size());
    for (Index r : rows_.deformable) image->states.push_back(rows_.states[r]);
    image->cluster_state = cluster_state_;
    image->prox = prox_;
    image->approx = approx_;
    return image;
  }
  void restore_image(const DetectorImage& image) override {
    const auto* mine = dynamic_cast<const Image*>(&image);
    if (!mine || mine->states.size() != rows_.deformable.size() || mine->cluster_state.size() != cluster_state_.size()) {
      throw Error(ErrorCode::Internal, "history", "detector image does not fit this approximate detector");
    }
    for (std::size_t q = 0; q < mine->states.size(); ++q) rows_.states[rows_.deformable[q]] = mine->states[q];
    cluster_state_ = mine->cluster_state;
    prox_ = mine->prox;
    approx_ = mine->approx;
  }
  std::unique_ptr<CollisionDetector> clone() const override { return std::make_unique<SimplifiedDetector>(*this); }

 private:
  // Distance of a simplified surfel to the zero region at its last proximity query.
  struct ProximityState {
    Vec3 center = Vec3::Zero();  // where it was measured
    double dist = 0.0;           // distance to the nearest zero surfel there, model units (0 = measure now)
  };
  // What detect() changes (save_image / restore_image).
  struct Image final : DetectorImage {
    std::vector<State> states;                // one per deformable row, in rows_.deformable order
    std::vector<State> cluster_state;         // #C
    std::vector<ProximityState> prox;         // #C
    ApproximateStats approx;
    std::size_t bytes() const override {
      return sizeof(*this) + (states.capacity() + cluster_state.capacity()) * sizeof(State) +
             prox.capacity() * sizeof(ProximityState);
    }
  };

  static Vec3 centroid(const Points& positions, const IndexList& rows) {
    Vec3 sum = Vec3::Zero();
    for (Index r : rows) sum += row3(positions, r);
    return sum / static_cast<double>(rows.size());
  }

  // The zero region: the kernel's (Simple, Temporal) or the detector's own (Robust).
  const ZeroSet& zero() const { return rows_.kernel.zero_set() ? *rows_.kernel.zero_set() : own_zero_; }

  SimplifyParams simplify_;
  KernelRows<Kernel> rows_;               // the exact algorithm's kernel, deformable rows, per-surfel states
  ZeroSet own_zero_;                      // zero region when the kernel has none: proximity, initial spheres
  ClusterMap clusters_;                   // deformable rows -> cluster
  std::vector<State> cluster_state_;      // #C: per simplified surfel (one-surfel clusters unused)
  std::vector<ProximityState> prox_;      // #C
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
    case CollisionAlgorithm::Simple: return std::make_unique<SimplifiedDetector<SimpleKernel>>(params, simplify);
    case CollisionAlgorithm::Temporal: return std::make_unique<SimplifiedDetector<TemporalKernel>>(params, simplify);
    case CollisionAlgorithm::Robust: break;
  }
  return std::make_unique<SimplifiedDetector<RobustHeldKernel>>(params, simplify);
}

}  // namespace surfeledit
