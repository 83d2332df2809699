// Collision detection with bounding volume hierarchies (docs/algorithms.md §5, thesis ch. 7-8): a broad
// phase over a zero tree (AABB, OBB or sphere boxes, one std::visit per step) and optionally a
// deformable AABB tree, in front of the configured algorithm's narrow test (collision_detail.hpp:
// NarrowDetector, the same code as without a hierarchy) or of the extended narrow phase.
//
// Broad phase. Each deformable surfel is bounded by the ball (p, r + |t|): its radius grown by its
// own displacement t this step, so the ball covers the whole path of its disc during the step. The
// zero tree bounds the balls (p2, r2) of the zero surfels. A surfel is a candidate when
//  - surfel/tree (no deformable tree): its ball overlaps a zero leaf box (Code 7.6);
//  - tree/tree: it lies in a deformable leaf whose box (refit each step over those balls, update =
//    bottom_up | top_down | hybrid; or, bounded, its last fit grown by the steps' largest displacement and
//    refit when it reaches a zero leaf, docs/algorithms.md §5) overlaps a zero leaf box (Code 8.4).
// Larger balls or boxes only add candidates: surfel/tree takes (p, r + the step's largest |t|).
// A non-candidate's ball misses every zero surfel ball: |p - p2| > r + |t| + r2 for all zero surfels,
// which is the step bound of §4.1, so Simple leaves its state unchanged -- the same colliding set
// as without a hierarchy, by construction. Temporal needs the nearest zero distance of every surfel
// that leaves its sphere anyway (for the next sphere), so it ignores the candidates and is exactly
// Temporal: detect() skips the broad phase for it. Robust has no step bound; a non-candidate did not
// come within its step of the zero surface, so its parity cannot have changed by crossing it (its
// inside state is re-derived once it is a candidate again, see RobustKernel::not_candidate in
// collision/robust_kernel.hpp); the tests check the equality on every step of the scenario scenes.
//
// Rebuild on idle (thesis §8.3.3): start_rebuild() builds a fresh deformable tree on a background
// thread (bvh::BvhRebuilder); detect() adopts it at its start when it is finished and the rows were
// neither inserted nor removed meanwhile (topology tag), then refits it as usual. No step waits.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <variant>

#include "collision_detail.hpp"
#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/bvh/extended.hpp"
#include "surfeledit/core/bvh/obb.hpp"
#include "surfeledit/core/bvh/rebuilder.hpp"
#include "surfeledit/core/bvh/sphere.hpp"
#include "surfeledit/core/bvh/traversal.hpp"
#include "surfeledit/core/inside_outside.hpp"
#include "surfeledit/core/simplify/sphere_tree.hpp"

namespace surfeledit {

void validate(const HierarchyParams& h, const CollisionParams& c) {
  bvh::validate(h.tree);
  if (h.zero == ZeroHierarchy::SphereHierarchical || h.zero == ZeroHierarchy::SphereIncremental) validate(h.clusters);
  if (h.zero > ZeroHierarchy::SphereIncremental) {
    throw Error(ErrorCode::InvalidArgument, "zero_hierarchy",
                "unknown zero hierarchy value " + std::to_string(static_cast<int>(h.zero)));
  }
  if (h.deformable > DeformableHierarchy::Aabb) {
    throw Error(ErrorCode::InvalidArgument, "deformable_hierarchy",
                "unknown deformable hierarchy value " + std::to_string(static_cast<int>(h.deformable)));
  }
  if (h.sat != bvh::SatMode::Lite && h.sat != bvh::SatMode::Full) {
    throw Error(ErrorCode::InvalidArgument, "sat", "unknown sat value " + std::to_string(static_cast<int>(h.sat)));
  }
  if (h.deformable != DeformableHierarchy::None && h.zero == ZeroHierarchy::None) {
    throw Error(ErrorCode::InvalidArgument, "deformable_hierarchy",
                std::string("deformable_hierarchy=") + to_string(h.deformable) +
                    " requires a zero_hierarchy (any but none): the deformable tree is tested against the zero tree");
  }
  if (h.extended && h.zero == ZeroHierarchy::None) {
    throw Error(ErrorCode::InvalidArgument, "extended", "extended=true requires a zero_hierarchy (any but none)");
  }
  if (!h.any() || c.algorithm == CollisionAlgorithm::None) return;
  if (h.extended && c.algorithm != CollisionAlgorithm::Robust) {
    throw Error(ErrorCode::InvalidArgument, "extended",
                std::string("extended=true tests against the original model as robust does: requires algorithm=robust, got ") +
                    to_string(c.algorithm));
  }
  if (c.algorithm == CollisionAlgorithm::Improved) {
    throw Error(ErrorCode::InvalidArgument, "zero_hierarchy",
                "algorithm=improved cannot run behind a hierarchy (its spatial coherence settles surfels from the "
                "queries of surfels the broad phase skips); use simple, temporal or robust, or zero_hierarchy=none");
  }
  if (!c.step_bound &&
      (c.algorithm == CollisionAlgorithm::Simple || c.algorithm == CollisionAlgorithm::Temporal)) {
    throw Error(ErrorCode::InvalidArgument, "zero_hierarchy",
                std::string("a hierarchy with algorithm=") + to_string(c.algorithm) +
                    " requires step_bound=true (the broad phase skips exactly the surfels the step bound keeps)");
  }
}

namespace detail {

namespace {

using ZeroTree = std::variant<bvh::Bvh<bvh::Aabb>, bvh::Bvh<bvh::Obb>, bvh::Bvh<bvh::Sphere>>;

class HierarchicalDetector final : public CollisionDetector {
 public:
  HierarchicalDetector(const CollisionParams& params, const HierarchyParams& h, std::unique_ptr<NarrowDetector> narrow)
      : CollisionDetector(params), h_(h), narrow_(std::move(narrow)) {}

  void reset(const CollisionScene& scene) override {
    const auto start = std::chrono::steady_clock::now();
    IndexList deformable, zero_rows;
    split_rows(scene, deformable, zero_rows);
    if (zero_rows.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region is empty");
    const Index rows = static_cast<Index>(scene.regions.size());
    // Narrow phase first (it validates the scene too).
    std::unique_ptr<bvh::ExtendedNarrow> extended;
    std::size_t extended_bytes = 0;
    if (h_.extended) {
      std::vector<std::uint8_t> is_zero(static_cast<std::size_t>(rows));
      for (Index r = 0; r < rows; ++r) is_zero[r] = scene.regions[r] == Region::Zero;
      KdTreeParams tp;
      tp.threads = resolve_threads(params_.threads);
      tp.eps = params_.knn_eps;
      auto original = std::make_shared<const InsideOutside>(scene.positions, scene.normals, tp);
      // Positions and normals copied by InsideOutside, its k-d tree, zero flags, cache and state per row.
      extended_bytes = original->tree().memory_bytes() + static_cast<std::size_t>(rows) * (6 * sizeof(double) + 18);
      extended = std::make_unique<bvh::ExtendedNarrow>(std::move(original), std::move(is_zero), rows, params_.threshold);
    } else {
      narrow_->reset(scene);
    }
    const auto t_zero = std::chrono::steady_clock::now();
    ZeroTree zero = build_zero(scene, zero_rows);
    zero_build_ms_ = ms_since(t_zero);
    std::unique_ptr<bvh::Bvh<bvh::Aabb>> def;
    def_build_ms_ = 0.0;
    if (h_.deformable == DeformableHierarchy::Aabb) {
      const auto t_def = std::chrono::steady_clock::now();
      def = std::make_unique<bvh::Bvh<bvh::Aabb>>(scene.positions, scene.radii, deformable, h_.tree);
      def_build_ms_ = ms_since(t_def);
    }
    zero_ = std::move(zero);
    def_ = std::move(def);
    extended_ = std::move(extended);
    deformable_ = std::move(deformable);
    rows_ = rows;
    bounded_ = !def_ || def_->bounded();
    zero_bounds_ = bvh::Aabb{};
    for (Index r : zero_rows) zero_bounds_.expand(row3(scene.positions, r), scene.radii[r]);
    if (bounded_) {
      reach_ = Values();
      prev_radius_.resize(deformable_.size());
      for (std::size_t q = 0; q < deformable_.size(); ++q) prev_radius_[q] = scene.radii[deformable_[q]];
    } else {
      reach_ = scene.radii;
      prev_radius_.clear();
    }
    candidate_.assign(static_cast<std::size_t>(rows_), 0);
    marked_.clear();
    inserted_nu_ = 0;
    rebuilds_adopted_ = 0;
    extended_bytes_ = extended_bytes;
    ++topology_;  // a rebuild started before the reset must not be adopted
    preprocess_ms_ = ms_since(start);
  }

  CollisionResult detect(const CollisionScene& scene, const Points& previous) override {
    const auto start = std::chrono::steady_clock::now();
    require_scene_rows(scene, rows_, "detect");
    if (previous.rows() != rows_) throw Error(ErrorCode::Internal, "previous", "row count differs from the scene");
    adopt_rebuilt_tree();
    for (Index r : marked_) candidate_[static_cast<std::size_t>(r)] = 0;  // last step's candidates
    marked_.clear();
    bvh::BvhCounters counters;
    counters.nu = inserted_nu_;  // boxes grown by insertions since the last step
    inserted_nu_ = 0;
    Index candidates = 0;
    // Temporal tests every surfel that leaves its sphere whether a candidate or not (not_candidate() is
    // update()): the broad phase cannot spare it anything, so it is skipped (exactly Temporal, nv = np = 0).
    const bool broad = extended_ || params_.algorithm != CollisionAlgorithm::Temporal;
    if (broad && !bounded_) {
      // Balls of this step: radius + own displacement (deformable rows; zero rows keep their radius).
      for (Index r : deformable_) {
        const double t = (row3(scene.positions, r) - row3(previous, r)).norm();
        reach_[r] = (scene.radii[r] + t) * (1.0 + 1e-9);
      }
    }
    if (broad && def_) {
      if (bounded_) {
        const Shift sh = step_shift(scene, previous);
        counters += def_->step_bounded(scene.positions, previous, scene.radii, sh.shift, sh.reach);
      } else {
        counters += def_->refit(scene.positions, reach_);
      }
      auto mark = [&](Index row) {
        candidate_[static_cast<std::size_t>(row)] = 1;
        marked_.push_back(row);
      };
      std::visit([&](const auto& zero) { bvh::collide(zero, *def_, h_.sat, mark, counters); }, zero_);
      candidates = counters.np;
    } else if (broad) {
      // Surfel/tree: each ball (p, r + the step's largest |t|) -- larger than (p, r + |t|), so no candidate
      // is lost -- first against the box of all zero balls, then down the zero tree.
      const double reach = step_shift(scene, previous).reach;
      const double* pos = scene.positions.data();
      const double* rad = scene.radii.data();
      const bvh::Aabb& all = zero_bounds_;
      std::visit(
          [&](const auto& zero) {
            for (Index r : deformable_) {
              const double* x = pos + 3 * static_cast<std::ptrdiff_t>(r);
              const double R = (rad[r] + reach) * (1.0 + 1e-9);
              ++counters.nv;
              if (x[0] + R < all.lo[0] || x[0] - R > all.hi[0] || x[1] + R < all.lo[1] || x[1] - R > all.hi[1] ||
                  x[2] + R < all.lo[2] || x[2] - R > all.hi[2])
                continue;
              const bvh::Sphere ball{row3(scene.positions, r), R};
              bvh::query_surfel(zero, ball, [&](std::int32_t) {
                candidate_[static_cast<std::size_t>(r)] = 1;
                marked_.push_back(r);
                ++candidates;
                return false;  // one overlapping leaf makes it a candidate
              }, counters, fifo_);
            }
          },
          zero_);
      counters.np = candidates;
    }
    CollisionResult result;
    if (extended_) {
      extended_->begin_step(++step_, scene.positions, previous);
      Index tested = 0;
      for (Index r : deformable_) {
        if (!candidate_[static_cast<std::size_t>(r)]) continue;
        (*extended_)(r);
        ++tested;
      }
      const std::vector<std::uint8_t>& colliding = extended_->colliding();
      result.stats.tested = tested;
      result.stats.queries = extended_->evaluations() - evaluations_;
      evaluations_ = extended_->evaluations();
      // The extended test keeps no spheres: no depth estimate. Timing is set below for both branches.
      collect_result(
          result, deformable_, [&](std::size_t, Index r) { return colliding[static_cast<std::size_t>(r)] != 0; },
          [](std::size_t, Index) { return 0.0; }, preprocess_ms_, start);
    } else {
      result = narrow_->detect_candidates(scene, previous, broad ? &candidate_ : nullptr);
    }
    result.stats.nv = counters.nv;
    result.stats.np = candidates;
    result.stats.nu = counters.nu;
    result.stats.preprocess_ms = preprocess_ms_;
    result.stats.detect_ms = ms_since(start);
    return result;
  }

  void on_removed(const std::vector<bool>& keep) override {
    if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
    if (extended_) {
      extended_->on_removed(keep);
    } else {
      narrow_->on_removed(keep);
    }
    const IndexList new_row = remap_rows(keep);
    std::visit([&](auto& zero) { zero.on_removed(keep); }, zero_);
    if (def_) def_->on_removed(keep);
    if (bounded_) {
      std::size_t w = 0;
      for (std::size_t q = 0; q < deformable_.size(); ++q)
        if (keep[static_cast<std::size_t>(deformable_[q])]) prev_radius_[w++] = prev_radius_[q];
      prev_radius_.resize(w);
    }
    deformable_ = remap_list(deformable_, keep, new_row);
    if (!bounded_) compact(reach_, keep);
    rows_ = static_cast<Index>(std::count(keep.begin(), keep.end(), true));
    candidate_.assign(static_cast<std::size_t>(rows_), 0);
    marked_.clear();
    ++topology_;
  }

  void on_inserted(const CollisionScene& scene, const IndexList& parents) override {
    const Index added = static_cast<Index>(parents.size());
    require_scene_rows(scene, rows_ + added, "on_inserted");
    if (extended_) {
      require_deformable_parents(scene, rows_, parents);
      extended_->on_inserted(parents);
    } else {
      narrow_->on_inserted(scene, parents);  // validates the parents
    }
    if (!bounded_) reach_.conservativeResize(rows_ + added);
    for (Index k = 0; k < added; ++k) {
      if (bounded_) prev_radius_.push_back(scene.radii[rows_ + k]);
      else reach_[rows_ + k] = scene.radii[rows_ + k];
      deformable_.push_back(rows_ + k);
    }
    // Each child joins its parent's leaf (zero tree: ignored, the parents are deformable).
    std::visit([&](auto& zero) { zero.on_inserted(scene.positions, scene.radii, parents); }, zero_);
    if (def_) inserted_nu_ += def_->on_inserted(scene.positions, bounded_ ? scene.radii : reach_, parents).nu;
    rows_ += added;
    candidate_.assign(static_cast<std::size_t>(rows_), 0);
    marked_.clear();
    ++topology_;
  }

  std::size_t memory_bytes() const override {
    std::size_t total = 0;
    for (const auto& s : structures()) total += s.second;
    return total;
  }

  std::vector<std::pair<std::string, std::size_t>> structures() const override {
    std::vector<std::pair<std::string, std::size_t>> out;
    if (extended_) {
      // The original model's inside/outside structure plus the per-row cache and state.
      out.emplace_back("collision_extended", extended_bytes_);
    } else {
      out.emplace_back(std::string("collision_") + to_string(params_.algorithm), narrow_->memory_bytes());
    }
    out.emplace_back(std::string("bvh_zero_") + to_string(h_.zero),
                     std::visit([](const auto& zero) { return zero.memory_bytes(); }, zero_));
    if (def_) out.emplace_back("bvh_deformable_aabb", def_->memory_bytes());
    out.emplace_back("bvh_scratch", static_cast<std::size_t>(reach_.size()) * sizeof(double) + candidate_.capacity() +
                                        deformable_.capacity() * sizeof(Index) +
                                        (prev_radius_.capacity() + marked_.capacity()) * sizeof(double));
    return out;
  }

  bool start_rebuild(const CollisionScene& scene) override {
    if (!def_) return false;
    require_scene_rows(scene, rows_, "start_rebuild");
    return rebuilder_.start(scene.positions, scene.radii, deformable_, h_.tree, topology_);
  }

  HierarchyInfo hierarchy_info() const override {
    HierarchyInfo info;
    info.status = def_ ? bvh::to_string(bvh::status_of(*def_, rebuilder_)) : "fresh";  // a zero tree is never refit
    info.zero_build_ms = zero_build_ms_;
    info.deformable_build_ms = def_build_ms_;
    info.last_rebuild_ms = last_rebuild_ms_;
    info.rebuilds_adopted = rebuilds_adopted_;
    return info;
  }

  // Undo (history.hpp). A step changes the narrow phase's states (or the extended narrow phase), the
  // deformable tree (refit, adopted rebuilds), the balls' reach and the step counters; the zero tree
  // changes only at reset, removal and insertion. The broad phase does not restrict detect_only(), so an
  // image always holds every deformable row (`rows` is ignored).
  std::shared_ptr<const DetectorImage> save_image(const IndexList*) const override {
    auto image = std::make_shared<Image>();
    if (extended_) {
      image->extended = std::make_shared<const bvh::ExtendedNarrow>(*extended_);
    } else {
      image->narrow = narrow_->save_image(nullptr);
      if (!image->narrow) return nullptr;
    }
    if (def_) image->def = std::make_shared<const bvh::Bvh<bvh::Aabb>>(*def_);
    if (bounded_) {
      image->reach = prev_radius_;  // the radii the next step's shift compares with
    } else {
      image->reach.reserve(deformable_.size());
      for (Index r : deformable_) image->reach.push_back(reach_[r]);
    }
    image->rows = rows_;
    image->step = step_;
    image->evaluations = evaluations_;
    image->inserted_nu = inserted_nu_;
    image->rebuilds_adopted = rebuilds_adopted_;
    return image;
  }
  void restore_image(const DetectorImage& image) override {
    const auto* mine = dynamic_cast<const Image*>(&image);
    if (!mine || mine->rows != rows_ || mine->reach.size() != deformable_.size() || !mine->extended != !extended_ ||
        !mine->def != !def_) {
      throw Error(ErrorCode::Internal, "history", "detector image does not fit this hierarchical detector");
    }
    if (extended_) *extended_ = *mine->extended;
    else narrow_->restore_image(*mine->narrow);
    if (def_) *def_ = *mine->def;
    if (bounded_) prev_radius_ = mine->reach;
    else for (std::size_t q = 0; q < deformable_.size(); ++q) reach_[deformable_[q]] = mine->reach[q];
    step_ = mine->step;
    evaluations_ = mine->evaluations;
    inserted_nu_ = mine->inserted_nu;
    rebuilds_adopted_ = mine->rebuilds_adopted;
  }
  // A deep copy (trees included); a background rebuild under way is not copied.
  std::unique_ptr<CollisionDetector> clone() const override {
    std::unique_ptr<CollisionDetector> narrow = narrow_->clone();
    if (!narrow) return nullptr;
    auto out = std::make_unique<HierarchicalDetector>(
        params_, h_, std::unique_ptr<NarrowDetector>(static_cast<NarrowDetector*>(narrow.release())));
    if (extended_) out->extended_ = std::make_unique<bvh::ExtendedNarrow>(*extended_);
    out->extended_bytes_ = extended_bytes_;
    out->zero_ = zero_;
    if (def_) out->def_ = std::make_unique<bvh::Bvh<bvh::Aabb>>(*def_);
    out->deformable_ = deformable_;
    out->rows_ = rows_;
    out->reach_ = reach_;
    out->bounded_ = bounded_;
    out->zero_bounds_ = zero_bounds_;
    out->prev_radius_ = prev_radius_;
    out->candidate_ = candidate_;
    out->marked_ = marked_;
    out->topology_ = topology_;
    out->step_ = step_;
    out->evaluations_ = evaluations_;
    out->inserted_nu_ = inserted_nu_;
    out->preprocess_ms_ = preprocess_ms_;
    out->zero_build_ms_ = zero_build_ms_;
    out->def_build_ms_ = def_build_ms_;
    out->last_rebuild_ms_ = last_rebuild_ms_;
    out->rebuilds_adopted_ = rebuilds_adopted_;
    return out;
  }

 private:
  // What detect() changes (save_image / restore_image); trees and the extended state are copies.
  struct Image final : DetectorImage {
    std::shared_ptr<const DetectorImage> narrow;             // narrow phase's image (without extended)
    std::shared_ptr<const bvh::ExtendedNarrow> extended;     // extended narrow phase (with it)
    std::shared_ptr<const bvh::Bvh<bvh::Aabb>> def;          // the deformable tree (with one)
    std::vector<double> reach;                               // per deformable row (bounded: its radius)
    Index rows = 0;
    std::int64_t step = 0, evaluations = 0;
    Index inserted_nu = 0, rebuilds_adopted = 0;
    std::size_t bytes() const override {
      return sizeof(*this) + (narrow ? narrow->bytes() : 0) + (def ? def->memory_bytes() : 0) +
             reach.capacity() * sizeof(double) +
             (extended ? extended->colliding().capacity() * (1 + 2 * sizeof(std::int64_t)) : 0);
    }
  };

  ZeroTree build_zero(const CollisionScene& scene, const IndexList& zero_rows) const {
    switch (h_.zero) {
      case ZeroHierarchy::Obb: return ZeroTree(std::in_place_index<1>, scene.positions, scene.radii, zero_rows, h_.tree);
      case ZeroHierarchy::Sphere:
        return ZeroTree(std::in_place_index<2>, scene.positions, scene.radii, zero_rows, h_.tree);
      case ZeroHierarchy::SphereHierarchical:
      case ZeroHierarchy::SphereIncremental: {
        const SphereClusterTree clusters =
            h_.zero == ZeroHierarchy::SphereHierarchical
                ? SphereClusterTree::build_hierarchical(scene.positions, scene.radii, zero_rows, h_.clusters)
                : SphereClusterTree::build_region_growing(scene.positions, scene.radii, zero_rows, h_.clusters);
        // Same layout as a Bvh: copy the nodes and let the tree derive its leaf map and step arrays.
        std::vector<bvh::BvhNode<bvh::Sphere>> nodes;
        nodes.reserve(clusters.nodes().size());
        for (const SphereTreeNode& c : clusters.nodes()) {
          bvh::BvhNode<bvh::Sphere> n;
          n.box = c.sphere;
          n.first_child = c.first_child;
          n.parent = c.parent;
          n.begin = c.begin;
          n.end = c.end;
          n.level = c.level;
          nodes.push_back(n);
        }
        ZeroTree tree(std::in_place_index<2>);
        std::get<2>(tree).adopt(std::move(nodes), clusters.order(), h_.tree);
        return tree;
      }
      case ZeroHierarchy::Aabb:
      case ZeroHierarchy::None: break;
    }
    return ZeroTree(std::in_place_index<0>, scene.positions, scene.radii, zero_rows, h_.tree);
  }

  // One pass over the deformable rows for a bounded tree's step (bvh.hpp, step_bounded): the largest
  // own displacement |p - previous| (reach) and that plus the largest radius growth since the last step
  // (shift); prev_radius_ takes the new radii. Squared lengths in the loop, one square root.
  struct Shift {
    double shift = 0.0, reach = 0.0;  // model units
  };
  Shift step_shift(const CollisionScene& scene, const Points& previous) {
    const double* p = scene.positions.data();
    const double* q = previous.data();
    const double* rad = scene.radii.data();
    double t2a = 0.0, t2b = 0.0, grow = 0.0;
    const std::size_t n = deformable_.size();
    auto d2 = [&](Index r) {
      const double* x = p + 3 * static_cast<std::ptrdiff_t>(r);
      const double* y = q + 3 * static_cast<std::ptrdiff_t>(r);
      const double a = x[0] - y[0], b = x[1] - y[1], c = x[2] - y[2];
      return a * a + b * b + c * c;
    };
    std::size_t k = 0;
    for (; k + 1 < n; k += 2) {  // two chains of maxima
      t2a = std::max(t2a, d2(deformable_[k]));
      t2b = std::max(t2b, d2(deformable_[k + 1]));
    }
    if (k < n) t2a = std::max(t2a, d2(deformable_[k]));
    for (k = 0; k < n; ++k) {
      const double r = rad[deformable_[k]];
      if (r != prev_radius_[k]) {
        grow = std::max(grow, r - prev_radius_[k]);
        prev_radius_[k] = r;
      }
    }
    Shift s;
    s.reach = std::sqrt(std::max(t2a, t2b)) * (1.0 + 1e-12);
    s.shift = (s.reach + grow) * (1.0 + 1e-12);
    return s;
  }

  // Swaps in a finished background rebuild (never waits); dropped when rows changed since it started.
  void adopt_rebuilt_tree() {
    if (!def_ || !rebuilder_.ready()) return;
    std::uint64_t tag = 0;
    std::unique_ptr<bvh::Bvh<bvh::Aabb>> tree = rebuilder_.take(&tag);
    if (!tree) return;
    last_rebuild_ms_ = rebuilder_.last_build_ms();
    if (tag != topology_) return;
    def_ = std::move(tree);
    // Its boxes are of the rows where they were when it started (an undo may have moved them since).
    if (bounded_) def_->refit_all_next_step();
    ++rebuilds_adopted_;
  }

  HierarchyParams h_;
  std::unique_ptr<NarrowDetector> narrow_;          // the algorithm's test (unused with extended)
  std::unique_ptr<bvh::ExtendedNarrow> extended_;   // extended narrow phase (extended = true)
  std::size_t extended_bytes_ = 0;                  // estimate of what extended_ holds
  ZeroTree zero_;                                   // over the zero rows; never refit (zero surfels do not move)
  std::unique_ptr<bvh::Bvh<bvh::Aabb>> def_;        // over the deformable rows (deformable_hierarchy = aabb)
  bvh::BvhRebuilder<bvh::Aabb> rebuilder_;          // background rebuild of def_
  IndexList deformable_;                            // rows with region != Zero, ascending
  Index rows_ = 0;                                  // rows of the model the state refers to
  Values reach_;                                    // #P: radius + own displacement this step (!bounded_)
  bool bounded_ = false;                            // no reach_: def_ uses the bounded update, or there is no def_
  bvh::Aabb zero_bounds_;                           // box of every zero ball (surfel/tree's first test)
  std::vector<double> prev_radius_;                 // bounded: by deformable_ index, its radius at the last step
  std::vector<std::uint8_t> candidate_;             // #P: 1 = candidate this step
  IndexList marked_;                                // the rows candidate_ holds set (cleared at the next step)
  std::vector<std::int32_t> fifo_;                  // scratch of the surfel/tree queue
  std::uint64_t topology_ = 0;                      // bumped by reset, insertions and removals
  std::int64_t step_ = 0;                           // steps of the extended narrow phase
  std::int64_t evaluations_ = 0;                    // extended evaluations counted so far
  Index inserted_nu_ = 0;                           // boxes grown by insertions (reported with the next step)
  double preprocess_ms_ = 0.0;                      // whole reset: narrow phase and trees
  double zero_build_ms_ = 0.0;                      // build of the zero tree
  double def_build_ms_ = 0.0;                       // build of the deformable tree
  double last_rebuild_ms_ = 0.0;                    // the last finished background rebuild
  Index rebuilds_adopted_ = 0;                      // background rebuilds swapped in since the reset
};

}  // namespace

std::unique_ptr<CollisionDetector> make_hierarchical_detector(const CollisionParams& params,
                                                              const HierarchyParams& hierarchy,
                                                              std::unique_ptr<NarrowDetector> narrow) {
  return std::make_unique<HierarchicalDetector>(params, hierarchy, std::move(narrow));
}

}  // namespace detail
}  // namespace surfeledit
