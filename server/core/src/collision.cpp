// Collision detection: algorithm names, parameter validation, the detector factories, and the
// pieces the detectors share (zero-region copy with boundary marks, the §4.1 test).
#include "surfeledit/core/collision.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "collision/improved_sweep.hpp"
#include "collision/kernel_snapshot.hpp"
#include "collision/robust_kernel.hpp"
#include "collision/row_detector.hpp"
#include "collision/temporal_kernel.hpp"
#include "collision_detail.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/simplify/approximate_detector.hpp"

namespace surfeledit {


void validate(const CollisionParams& p) {
  switch (p.algorithm) {
    case CollisionAlgorithm::None:
    case CollisionAlgorithm::Simple:
    case CollisionAlgorithm::Improved:
    case CollisionAlgorithm::Temporal:
    case CollisionAlgorithm::Robust: break;
    default:
      throw Error(ErrorCode::InvalidArgument, "algorithm",
                  "unknown collision algorithm value " + std::to_string(static_cast<int>(p.algorithm)));
  }
  if (!std::isfinite(p.threshold)) {
    std::ostringstream msg;
    msg << "must be finite, got " << p.threshold;
    throw Error(ErrorCode::InvalidArgument, "threshold", msg.str());
  }
  if (p.boundary_n < 1) {
    throw Error(ErrorCode::InvalidArgument, "boundary_n", "must be >= 1, got " + std::to_string(p.boundary_n));
  }
  if (p.boundary_i < 1 || p.boundary_i > p.boundary_n) {
    throw Error(ErrorCode::InvalidArgument, "boundary_i",
                "must be in 1..boundary_n (" + std::to_string(p.boundary_n) + "), got " +
                    std::to_string(p.boundary_i));
  }
  if (p.threads < 0) {
    throw Error(ErrorCode::InvalidArgument, "threads", "must be >= 0, got " + std::to_string(p.threads));
  }
  if (!std::isfinite(p.parallel_min_ms) || p.parallel_min_ms < 0.0) {
    std::ostringstream msg;
    msg << "must be finite and >= 0, got " << p.parallel_min_ms;
    throw Error(ErrorCode::InvalidArgument, "parallel_min_ms", msg.str());
  }
  if (!std::isfinite(p.knn_eps) || p.knn_eps < 0.0) {
    std::ostringstream msg;
    msg << "must be finite and >= 0, got " << p.knn_eps;
    throw Error(ErrorCode::InvalidArgument, "knn_eps", msg.str());
  }
  if (!std::isfinite(p.sphere_margin) || p.sphere_margin < 0.0) {
    std::ostringstream msg;
    msg << "must be finite and >= 0, got " << p.sphere_margin;
    throw Error(ErrorCode::InvalidArgument, "sphere_margin", msg.str());
  }
  detail::validate_inside(p);
}

std::unique_ptr<CollisionDetector> CollisionDetector::create(const CollisionParams& params,
                                                             const HierarchyParams& hierarchy) {
  validate(params);
  validate(hierarchy, params);
  if (params.algorithm == CollisionAlgorithm::None) return nullptr;
  std::unique_ptr<detail::NarrowDetector> narrow = detail::make_narrow_detector(params);
  if (!hierarchy.any()) return narrow;
  return detail::make_hierarchical_detector(params, hierarchy, std::move(narrow));
}

std::vector<std::pair<std::string, std::size_t>> CollisionDetector::structures() const {
  return {{std::string("collision_") + to_string(params_.algorithm), memory_bytes()}};
}

bool CollisionDetector::on_rigid_moved(const CollisionScene&, const IndexList&, const RigidRows&) { return false; }

bool CollisionDetector::start_rebuild(const CollisionScene&) { return false; }

HierarchyInfo CollisionDetector::hierarchy_info() const { return {}; }

CollisionResult CollisionDetector::detect_only(const CollisionScene& scene, const Points& previous,
                                               const std::vector<std::uint8_t>&) {
  return detect(scene, previous);
}

std::shared_ptr<const DetectorImage> CollisionDetector::save_image(const IndexList*) const { return nullptr; }

void CollisionDetector::restore_image(const DetectorImage&) {
  throw Error(ErrorCode::Internal, "history", "this detector saves no images");
}

std::unique_ptr<CollisionDetector> CollisionDetector::clone() const { return nullptr; }

bool CollisionDetector::start_journal() { return false; }

std::shared_ptr<const DetectorImage> CollisionDetector::journal_image() const { return nullptr; }

void CollisionDetector::restore_journal() {
  throw Error(ErrorCode::Internal, "history", "this detector keeps no journal");
}

bool CollisionDetector::journal_tested(std::vector<std::uint8_t>&) const { return false; }

void CollisionDetector::stop_journal() {}

std::unique_ptr<CollisionDetector> make_detector(const SessionSettings& settings) {
  SimplifyParams clusters = settings.simplify;
  clusters.threads = settings.collision.threads;
  // Clusters of the deformable region: approximate detection.
  if (clusters.method != SimplifyMethod::None && settings.collision.algorithm != CollisionAlgorithm::None) {
    return make_approximate_detector(settings.collision, clusters);
  }
  HierarchyParams hierarchy = settings.hierarchy;
  hierarchy.clusters = clusters;  // leaves of sphere cluster trees (unused by the other kinds)
  return CollisionDetector::create(settings.collision, hierarchy);
}

namespace detail {

std::unique_ptr<NarrowDetector> make_narrow_detector(const CollisionParams& params) {
  switch (params.algorithm) {
    case CollisionAlgorithm::Simple: return std::make_unique<RowDetector<SimpleKernel>>(params);
    case CollisionAlgorithm::Improved: return std::make_unique<RowDetector<SimpleKernel, ImprovedSweep>>(params);
    case CollisionAlgorithm::Temporal: return std::make_unique<RowDetector<TemporalKernel>>(params);
    case CollisionAlgorithm::Robust: return std::make_unique<RowDetector<RobustKernel>>(params);
    case CollisionAlgorithm::None: break;
  }
  throw Error(ErrorCode::Internal, "algorithm", "no detector for algorithm none");
}

void require_scene_rows(const CollisionScene& scene, Index rows, const char* what) {
  const Eigen::Index n = rows;
  if (scene.positions.rows() != n || scene.normals.rows() != n || scene.radii.size() != n ||
      static_cast<Eigen::Index>(scene.regions.size()) != n) {
    std::ostringstream msg;
    msg << what << ": the detector holds " << rows << " rows but the scene has positions "
        << scene.positions.rows() << ", normals " << scene.normals.rows() << ", radii " << scene.radii.size()
        << ", regions " << scene.regions.size();
    throw Error(ErrorCode::Internal, "scene", msg.str());
  }
}

void split_rows(const CollisionScene& scene, IndexList& deformable, IndexList& zero) {
  deformable.clear();
  zero.clear();
  for (std::size_t r = 0; r < scene.regions.size(); ++r)
    (scene.regions[r] == Region::Zero ? zero : deformable).push_back(static_cast<Index>(r));
}

IndexList remap_list(const IndexList& rows, const std::vector<bool>& keep, const IndexList& new_row) {
  IndexList out;
  out.reserve(rows.size());
  for (Index r : rows)
    if (keep[r]) out.push_back(new_row[r]);
  return out;
}

void require_deformable_parents(const CollisionScene& scene, Index rows, const IndexList& parents) {
  for (std::size_t k = 0; k < parents.size(); ++k) {
    const Index q = parents[k];
    if (q < 0 || q >= rows || scene.regions[q] == Region::Zero ||
        scene.regions[rows + static_cast<Index>(k)] == Region::Zero) {
      throw Error(ErrorCode::InvalidArgument, "parents", "inserted surfels must be split from deformable rows");
    }
  }
}

void ZeroSet::build(const CollisionScene& scene, const IndexList& zero_rows, double eps, bool with_cells) {
  knn_eps = eps;
  cells = with_cells;
  if (zero_rows.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region is empty");
  const Eigen::Index z = static_cast<Eigen::Index>(zero_rows.size());
  positions.resize(z, 3);
  normals.resize(z, 3);
  radii.resize(z);
  for (Eigen::Index k = 0; k < z; ++k) {
    const Index r = zero_rows[static_cast<std::size_t>(k)];
    positions.row(k) = scene.positions.row(r);
    normals.row(k) = scene.normals.row(r);
    radii[k] = scene.radii[r];
  }
  rows = zero_rows;
  marked.assign(zero_rows.size(), 0);
  tree = std::make_unique<KdTree>(positions, tree_params());
}

double ZeroSet::move_rows(const CollisionScene& scene, const IndexList& moved) {
  IndexList at(moved.size());
  for (std::size_t j = 0; j < moved.size(); ++j) {
    const auto it = std::lower_bound(rows.begin(), rows.end(), moved[j]);
    if (it == rows.end() || *it != moved[j]) return -1.0;  // not a zero row of this set
    at[j] = static_cast<Index>(it - rows.begin());
  }
  double reach = 0.0;
  for (std::size_t j = 0; j < moved.size(); ++j) {
    const Index r = moved[j], k = at[j];
    reach = std::max(reach, (positions.row(k) - scene.positions.row(r)).norm());
    positions.row(k) = scene.positions.row(r);
    normals.row(k) = scene.normals.row(r);
    radii[k] = scene.radii[r];
  }
  // A new tree: the old one may be shared by clones (history images) that keep the old positions.
  if (!moved.empty()) tree = std::make_shared<const KdTree>(positions, tree_params());
  return reach;
}

IndexList ZeroSet::rows_near_zero(const CollisionScene& scene, const IndexList& deformable, const KdTree& whole,
                                  int k, int threads, KnnResult* nearest) const {
  const Eigen::Index n = static_cast<Eigen::Index>(deformable.size());
  Points queries(n, 3);
  for (Eigen::Index q = 0; q < n; ++q) queries.row(q) = scene.positions.row(deformable[static_cast<std::size_t>(q)]);
  KnnResult zero = tree->knn(queries, 1, threads);
  // The two trees round their distances in their own local frames (centred, maybe turned): each squared distance is
  // off by a few ulps of the model's extent. A point counts as closer than the nearest zero surfel only below its
  // distance less a margin well above that (and less the share an approximate zero tree may overshoot by).
  double extent = 0.0;
  if (scene.positions.rows() > 0) {
    const Vec3 lo = scene.positions.colwise().minCoeff().transpose(), hi = scene.positions.colwise().maxCoeff().transpose();
    extent = (hi - lo).norm() + std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  }
  const double slack = 64.0 * std::numeric_limits<double>::epsilon() * extent;
  std::vector<std::uint8_t> keep(static_cast<std::size_t>(n), 1);
#pragma omp parallel for schedule(dynamic, 256) num_threads(resolve_threads(threads))
  for (Eigen::Index q = 0; q < n; ++q) {
    const double d = std::sqrt(zero.dist2(q, 0) / (1.0 + knn_eps)) * (1.0 - 1e-9) - slack;
    if (d > 0.0 && whole.count_within(queries.row(q).transpose(), d * d, k) >= k) keep[static_cast<std::size_t>(q)] = 0;
  }
  IndexList out;
  for (Eigen::Index q = 0; q < n; ++q)
    if (keep[static_cast<std::size_t>(q)]) out.push_back(deformable[static_cast<std::size_t>(q)]);
  if (nearest) *nearest = std::move(zero);
  return out;
}

void ZeroSet::mark_boundary(const CollisionScene& scene, const IndexList& deformable, const KdTree& whole, int n,
                            int i, int threads, KnnResult* nearest) {
  std::fill(marked.begin(), marked.end(), 0);
  if (deformable.empty()) {
    if (nearest) *nearest = KnnResult();
    return;
  }
  // Row -> index into the zero copies (-1 for deformable rows).
  IndexList zero_of_row(scene.regions.size(), -1);
  for (std::size_t k = 0; k < rows.size(); ++k) zero_of_row[rows[k]] = static_cast<Index>(k);
  // Only a row with a zero surfel among its n + 1 nearest can mark one. A row with n + 1 points strictly closer than
  // its nearest zero surfel has none there, whatever the order of ties, and makes no knn query: most deformable rows
  // lie far from the zero region, where such points are found in a leaf (RESULTS §75).
  const IndexList near = rows_near_zero(scene, deformable, whole, n + 1, threads, nearest);
  Points queries(static_cast<Eigen::Index>(near.size()), 3);
  for (std::size_t q = 0; q < near.size(); ++q) queries.row(q) = scene.positions.row(near[q]);
  // n + 1 neighbours: the surfel itself comes back too and is skipped.
  const KnnResult knn = whole.knn(queries, n + 1);
  for (std::size_t q = 0; q < near.size(); ++q) {
    int seen = 0, marks = 0;
    for (Eigen::Index j = 0; j < knn.indices.cols() && seen < n && marks < i; ++j) {
      const Index r = knn.indices(q, j);
      if (r < 0 || r == near[q]) continue;
      ++seen;
      const Index z = zero_of_row[r];
      if (z >= 0) {
        marked[z] = 1;
        ++marks;
      }
    }
  }
}

void ZeroSet::on_removed(const std::vector<bool>& keep, const IndexList& new_row) {
  std::vector<bool> keep_zero(rows.size());
  bool any_removed = false;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    keep_zero[k] = keep[rows[k]];
    any_removed |= !keep_zero[k];
  }
  if (!any_removed) {
    for (Index& r : rows) r = new_row[r];
    return;
  }
  compact(positions, keep_zero);
  compact(normals, keep_zero);
  compact(radii, keep_zero);
  compact(marked, keep_zero);
  compact(rows, keep_zero);
  for (Index& r : rows) r = new_row[r];
  if (rows.empty()) throw Error(ErrorCode::Internal, "regions", "every zero surfel was removed");
  tree = std::make_unique<KdTree>(positions, tree_params());
}

std::size_t ZeroSet::memory_bytes() const {
  return static_cast<std::size_t>(positions.size() + normals.size() + radii.size()) * sizeof(double) +
         marked.capacity() + rows.capacity() * sizeof(Index) + (tree ? tree->memory_bytes() : 0);
}

SimpleTest simple_test(const CollisionParams& params, const ZeroSet& zero, Index k, const Vec3& p1, double r1,
                       const Vec3& previous, bool previous_state, bool bounded) {
  SimpleTest out;
  const Vec3 d = p1 - zero.positions.row(k).transpose();
  out.dist2 = d.squaredNorm();
  if (params.step_bound && bounded) {
    // Def. 6.1 with the surfel's own displacement t this step: farther than |t| + r1 + r2 from the
    // nearest zero surfel, it cannot have crossed the zero surface.
    const double bound = (p1 - previous).norm() + r1 + zero.radii[k];
    if (out.dist2 > bound * bound) {
      out.state = previous_state;
      return out;
    }
  }
  const bool inside = d.dot(zero.normals.row(k).transpose()) < params.threshold;
  out.state = inside && !(params.boundary && zero.marked[static_cast<std::size_t>(k)]);
  return out;
}

}  // namespace detail
}  // namespace surfeledit
