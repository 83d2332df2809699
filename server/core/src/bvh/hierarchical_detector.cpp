// The hierarchical detector (hierarchical_detector.hpp): reset, the broad phase in front of the narrow test,
// row removals and insertions, background rebuilds and what it reports.
#include "hierarchical_detector.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <variant>

#include "../at_once.hpp"
#include "surfeledit/core/bvh/traversal.hpp"
#include "surfeledit/core/inside_outside.hpp"

namespace surfeledit::detail {

void HierarchicalDetector::reset(const CollisionScene& scene) {
  const auto start = std::chrono::steady_clock::now();
  IndexList deformable, zero_rows;
  split_rows(scene, deformable, zero_rows);
  if (zero_rows.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region is empty");
  const Index rows = static_cast<Index>(scene.regions.size());
  const int threads = resolve_threads(params_.threads);
  // The narrow phase (first: it validates the scene too) and the broad phase's trees share nothing: with threads > 1
  // on a large model they are built at once (at_once.hpp; the narrow phase's own parts then run one after the other
  // on its thread), the same detector as one after the other.
  std::unique_ptr<bvh::ExtendedNarrow> extended;
  std::size_t extended_bytes = 0;
  auto narrow = [&] {
    if (h_.extended) {
      std::vector<std::uint8_t> is_zero(static_cast<std::size_t>(rows));
      for (Index r = 0; r < rows; ++r) is_zero[r] = scene.regions[r] == Region::Zero;
      KdTreeParams tp;
      tp.threads = threads;
      tp.eps = params_.knn_eps;
      auto original = std::make_shared<const InsideOutside>(scene.positions, scene.normals, tp);
      // Positions and normals copied by InsideOutside, its k-d tree, zero flags, cache and state per row.
      extended_bytes = original->tree().memory_bytes() + static_cast<std::size_t>(rows) * (6 * sizeof(double) + 18);
      extended = std::make_unique<bvh::ExtendedNarrow>(std::move(original), std::move(is_zero), rows, params_.threshold);
    } else {
      narrow_->reset(scene);
    }
  };
  ZeroTree zero;
  std::unique_ptr<bvh::Bvh<bvh::Aabb>> def;
  double zero_ms = 0.0, def_ms = 0.0;  // the members take them once the reset succeeded
  auto broad = [&] {
    const auto t_zero = std::chrono::steady_clock::now();
    zero = build_zero_tree(scene, zero_rows, h_);
    zero_ms = ms_since(t_zero);
    if (h_.deformable == DeformableHierarchy::Aabb) {
      const auto t_def = std::chrono::steady_clock::now();
      def = std::make_unique<bvh::Bvh<bvh::Aabb>>(scene.positions, scene.radii, deformable, h_.tree);
      def_ms = ms_since(t_def);
    }
  };
  at_once(at_once_pays(threads, scene.regions.size()), narrow, broad);
  zero_build_ms_ = zero_ms;
  def_build_ms_ = def_ms;
  // Surfel/tree behind a broad phase: the filter tree and the zero hull (not for Temporal, which has none).
  std::unique_ptr<bvh::Bvh<bvh::Aabb>> filter;
  bvh::Aabb hull;
  for (Index r : zero_rows) hull.expand(row3(scene.positions, r), scene.radii[r]);
  if (!def && (h_.extended || params_.algorithm != CollisionAlgorithm::Temporal)) {
    bvh::BvhParams fp = h_.tree;
    fp.update = bvh::UpdateMode::Bounded;
    filter = std::make_unique<bvh::Bvh<bvh::Aabb>>(scene.positions, scene.radii, deformable, fp);
    bvh::BvhNode<bvh::Aabb> leaf;
    leaf.box = hull;
    zero_hull_.adopt({leaf}, IndexList(), fp);
  } else {
    zero_hull_ = bvh::Bvh<bvh::Aabb>();
  }
  drop_journal();
  zero_ = std::move(zero);
  def_ = std::move(def);
  filter_ = std::move(filter);
  extended_ = std::move(extended);
  deformable_ = std::move(deformable);
  rows_ = rows;
  bounded_ = !def_ || def_->bounded();
  zero_bounds_ = hull;
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

CollisionResult HierarchicalDetector::detect(const CollisionScene& scene, const Points& previous) {
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
      const StepShift sh = shift_of(scene, previous);
      counters += def_->step_bounded(scene.positions, previous, scene.radii, sh.shift, sh.reach);
    } else {
      counters += def_->refit(scene.positions, reach_);
    }
    auto mark = [&](Index row) {
      candidate_[static_cast<std::size_t>(row)] = 1;
      marked_.push_back(row);
    };
    // The hull of the zero balls prunes too where the zero boxes are looser than an AABB (OBB, sphere).
    const bvh::Aabb* hull = std::holds_alternative<bvh::Bvh<bvh::Aabb>>(zero_) ? nullptr : &zero_bounds_;
    std::visit([&](const auto& zero) { bvh::collide(zero, *def_, h_.sat, mark, counters, hull); }, zero_);
    candidates = counters.np;
  } else if (broad) {
    candidates = surfel_tree(scene, previous, counters);
    counters.np = candidates;
  }
  if (broad && !extended_) candidates += near_open_boundary(scene, previous);
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

Index HierarchicalDetector::surfel_tree(const CollisionScene& scene, const Points& previous, bvh::BvhCounters& counters) {
  // Each ball (p, r + the step's largest |t|) -- larger than (p, r + |t|), so no candidate is lost -- first
  // against the box of all zero balls, then down the zero tree.
  const StepShift sh = shift_of(scene, previous);
  const double reach = sh.reach;
  const double* pos = scene.positions.data();
  const double* rad = scene.radii.data();
  const bvh::Aabb& all = zero_bounds_;
  Index candidates = 0;
  std::visit(
      [&](const auto& zero) {
        auto test = [&](Index r) {
          const double* x = pos + 3 * static_cast<std::ptrdiff_t>(r);
          const double R = (rad[r] + reach) * (1.0 + 1e-9);
          ++counters.nv;
          if (x[0] + R < all.lo[0] || x[0] - R > all.hi[0] || x[1] + R < all.lo[1] || x[1] - R > all.hi[1] ||
              x[2] + R < all.lo[2] || x[2] - R > all.hi[2])
            return;
          const bvh::Sphere ball{row3(scene.positions, r), R};
          bvh::query_surfel(zero, ball, [&](std::int32_t) {
            candidate_[static_cast<std::size_t>(r)] = 1;
            marked_.push_back(r);
            ++candidates;
            return false;  // one overlapping leaf makes it a candidate
          }, counters, fifo_);
        };
        if (!filter_) {
          for (Index r : deformable_) test(r);
          return;
        }
        // The filter's leaf boxes bound the balls (p, r + |t|) (bounded update, bvh_bounded-inl.hpp): a row
        // outside every leaf that reaches the box of all zero balls has a ball (p, r + |t|) missing it, so it
        // is no candidate by the argument above (the ball the test uses only adds candidates).
        counters += filter_->step_bounded(scene.positions, previous, scene.radii, sh.shift, sh.reach);
        bvh::collide(zero_hull_, *filter_, bvh::SatMode::Lite, test, counters);
      },
      zero_);
  return candidates;
}

Index HierarchicalDetector::near_open_boundary(const CollisionScene& scene, const Points& previous) {
  const std::vector<ZeroBall> balls = narrow_->open_boundary(scene);
  if (balls.empty()) return 0;
  Index marked = 0;
  for (Index r : deformable_) {
    if (candidate_[static_cast<std::size_t>(r)]) continue;
    const Vec3 p = row3(scene.positions, r);
    const double reach = (scene.radii[r] + (p - row3(previous, r)).norm()) * (1.0 + 1e-9);
    for (const ZeroBall& b : balls) {
      if ((p - b.center).norm() <= reach + b.radius) {
        candidate_[static_cast<std::size_t>(r)] = 1;
        marked_.push_back(r);
        ++marked;
        break;
      }
    }
  }
  return marked;
}

StepShift HierarchicalDetector::shift_of(const CollisionScene& scene, const Points& previous) {
  if (!scene.displacement_bound) {
    keep_journal_reach();  // step_shift() takes the new radii
    return step_shift(scene, previous, deformable_, prev_radius_);
  }
  const double bound = *checked_displacement_bound(scene);
#ifndef NDEBUG
  // The measured values (the pass the bound spares) must not exceed it: displacement and radius growth.
  const StepShift measured = step_shift(scene, previous, deformable_, prev_radius_);
  if (measured.shift > bound * (1.0 + 1e-9)) {
    throw Error(ErrorCode::Internal, "displacement_bound",
                "handed-over bound " + std::to_string(bound) + " below the measured " + std::to_string(measured.shift));
  }
#endif
  return StepShift{bound, bound};  // no radius changed: the shift is the displacement
}

void HierarchicalDetector::on_removed(const std::vector<bool>& keep) {
  if (static_cast<Index>(keep.size()) != rows_) throw Error(ErrorCode::Internal, "keep", "row count differs");
  drop_journal();
  if (extended_) {
    extended_->on_removed(keep);
  } else {
    narrow_->on_removed(keep);
  }
  const IndexList new_row = remap_rows(keep);
  std::visit([&](auto& zero) { zero.on_removed(keep); }, zero_);
  if (def_) def_->on_removed(keep);
  if (filter_) filter_->on_removed(keep);
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

void HierarchicalDetector::on_inserted(const CollisionScene& scene, const IndexList& parents) {
  const Index added = static_cast<Index>(parents.size());
  require_scene_rows(scene, rows_ + added, "on_inserted");
  drop_journal();
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
  if (filter_) inserted_nu_ += filter_->on_inserted(scene.positions, scene.radii, parents).nu;
  rows_ += added;
  candidate_.assign(static_cast<std::size_t>(rows_), 0);
  marked_.clear();
  ++topology_;
}

std::size_t HierarchicalDetector::memory_bytes() const {
  std::size_t total = 0;
  for (const auto& s : structures()) total += s.second;
  return total;
}

std::vector<std::pair<std::string, std::size_t>> HierarchicalDetector::structures() const {
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
  if (filter_) out.emplace_back("bvh_surfel_filter", filter_->memory_bytes() + zero_hull_.memory_bytes());
  out.emplace_back("bvh_scratch", static_cast<std::size_t>(reach_.size()) * sizeof(double) + candidate_.capacity() +
                                      deformable_.capacity() * sizeof(Index) +
                                      (prev_radius_.capacity() + marked_.capacity()) * sizeof(double));
  return out;
}

bool HierarchicalDetector::start_rebuild(const CollisionScene& scene) {
  if (!def_) return false;
  require_scene_rows(scene, rows_, "start_rebuild");
  return rebuilder_.start(scene.positions, scene.radii, deformable_, h_.tree, topology_);
}

HierarchyInfo HierarchicalDetector::hierarchy_info() const {
  HierarchyInfo info;
  info.status = def_ ? bvh::to_string(bvh::status_of(*def_, rebuilder_)) : "fresh";  // a zero tree is never refit
  info.zero_build_ms = zero_build_ms_;
  info.deformable_build_ms = def_build_ms_;
  info.last_rebuild_ms = last_rebuild_ms_;
  info.rebuilds_adopted = rebuilds_adopted_;
  return info;
}

void HierarchicalDetector::adopt_rebuilt_tree() {
  if (!def_ || !rebuilder_.ready()) return;
  std::uint64_t tag = 0;
  std::unique_ptr<bvh::Bvh<bvh::Aabb>> tree = rebuilder_.take(&tag);
  if (!tree) return;
  last_rebuild_ms_ = rebuilder_.last_build_ms();
  if (tag != topology_) return;
  keep_journal_tree();
  def_ = std::move(tree);
  // Its boxes are of the rows where they were when it started (an undo may have moved them since).
  if (bounded_) def_->refit_all_next_step();
  ++rebuilds_adopted_;
}

std::unique_ptr<CollisionDetector> make_hierarchical_detector(const CollisionParams& params,
                                                              const HierarchyParams& hierarchy,
                                                              std::unique_ptr<NarrowDetector> narrow) {
  return std::make_unique<HierarchicalDetector>(params, hierarchy, std::move(narrow));
}

}  // namespace surfeledit::detail
