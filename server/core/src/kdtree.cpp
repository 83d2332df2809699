// k-d tree over 3-D points: nanoflann (static index, sliding-midpoint split) behind a pimpl.
#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <sstream>
#include <utility>

namespace surfeledit {

namespace {

// Points in the tree's local frame: #N by 3 packed xyz, relative to `origin` (their centroid).
struct LocalCloud {
  std::vector<double> xyz;  // 3 * #N
  inline std::size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  inline double kdtree_get_pt(std::uint32_t i, std::size_t dim) const { return xyz[3 * i + dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, LocalCloud>,
                                                     LocalCloud, 3, std::uint32_t>;

// Radius result set with an INCLUSIVE bound: keeps every point with dist2 <= r2.
// nanoflann's leaf test is `dist2 < worstDist()`, so worstDist() reports the next double above r2.
class InclusiveRadiusSet {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  InclusiveRadiusSet(double r2, std::vector<std::pair<std::uint32_t, double>>& out)
      : r2_(r2), bound_(std::nextafter(r2, std::numeric_limits<double>::infinity())), out_(out) {
    out_.clear();
  }
  std::size_t size() const { return out_.size(); }
  bool full() const { return true; }
  bool addPoint(double dist2, std::uint32_t index) {
    if (dist2 <= r2_) out_.emplace_back(index, dist2);
    return true;
  }
  double worstDist() const { return bound_; }

 private:
  double r2_;
  double bound_;
  std::vector<std::pair<std::uint32_t, double>>& out_;
};


void check_params(const KdTreeParams& params) {
  if (params.leaf_size < 1) {
    throw Error(ErrorCode::InvalidArgument, "leaf_size",
                "leaf size must be >= 1, got " + std::to_string(params.leaf_size));
  }
  if (params.threads < 0) {
    throw Error(ErrorCode::InvalidArgument, "threads",
                "thread count must be >= 0, got " + std::to_string(params.threads));
  }
  if (!(params.eps >= 0.0) || !std::isfinite(params.eps)) {
    throw Error(ErrorCode::InvalidArgument, "eps",
                "approximate-search eps must be finite and >= 0, got " + std::to_string(params.eps));
  }
}

void check_query(const Vec3& q) {
  if (!q.allFinite()) {
    std::ostringstream msg;
    msg << "query point must be finite, got (" << q.x() << ", " << q.y() << ", " << q.z() << ")";
    throw Error(ErrorCode::InvalidArgument, "query", msg.str());
  }
}

}  // namespace

struct KdTree::Impl {
  KdTreeParams params;
  Vec3 origin = Vec3::Zero();  // centroid of the tree's points, world units
  LocalCloud cloud;            // points minus origin
  std::vector<Index> rows;     // tree point i -> row of the caller's array; empty = identity
  std::unique_ptr<NanoTree> tree;

  Impl(const Points& points, const IndexList* subset, KdTreeParams p) : params(p) {
    check_params(params);
    const Eigen::Index n_all = points.rows();
    if (subset) {
      for (std::size_t i = 0; i < subset->size(); ++i) {
        const Index r = (*subset)[i];
        if (r < 0 || r >= n_all) {
          std::ostringstream msg;
          msg << "subset entry " << i << " = " << r << " is out of range [0, " << n_all << ")";
          throw Error(ErrorCode::InvalidArgument, "subset", msg.str());
        }
        if (!points.row(r).allFinite()) {
          throw Error(ErrorCode::InvalidArgument, "points",
                      "non-finite point at row " + std::to_string(r));
        }
      }
      rows.assign(subset->begin(), subset->end());
    } else {
      if (n_all > static_cast<Eigen::Index>(std::numeric_limits<Index>::max())) {
        throw Error(ErrorCode::TooLarge, "points", "too many points: " + std::to_string(n_all));
      }
      require_finite(points, "points");
    }
    const std::size_t n = subset ? subset->size() : static_cast<std::size_t>(n_all);
    auto row_of = [&](std::size_t i) -> Index { return subset ? (*subset)[i] : static_cast<Index>(i); };
    // Centroid by a shifted mean (relative to the first point) to keep precision far from the origin.
    if (n > 0) {
      const Vec3 ref = points.row(row_of(0)).transpose();
      Vec3 sum = Vec3::Zero();
      for (std::size_t i = 0; i < n; ++i) sum += points.row(row_of(i)).transpose() - ref;
      origin = ref + sum / static_cast<double>(n);
    }
    cloud.xyz.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
      const Index r = row_of(i);
      for (int d = 0; d < 3; ++d) cloud.xyz[3 * i + d] = points(r, d) - origin[d];
    }
    tree = std::make_unique<NanoTree>(3, cloud,
                                      nanoflann::KDTreeSingleIndexAdaptorParams(
                                          static_cast<std::size_t>(params.leaf_size)));
  }

  Index to_row(std::uint32_t i) const { return rows.empty() ? static_cast<Index>(i) : rows[i]; }
  std::size_t count() const { return cloud.kdtree_get_point_count(); }

  // k nearest of q (world units); writes up to k (index, dist2) pairs, returns how many.
  std::size_t knn_raw(const Vec3& q, std::size_t k, std::uint32_t* idx, double* d2) const {
    if (k == 0 || count() == 0) return 0;
    const double local[3] = {q.x() - origin.x(), q.y() - origin.y(), q.z() - origin.z()};
    nanoflann::KNNResultSet<double, std::uint32_t> set(k);
    set.init(idx, d2);
    tree->findNeighbors(set, local, nanoflann::SearchParams(32, static_cast<float>(params.eps)));
    return set.size();
  }

  // All points with dist2 <= r2 of q, sorted by dist2.
  void radius_raw(const Vec3& q, double r2, std::vector<std::pair<std::uint32_t, double>>& out) const {
    out.clear();
    if (count() == 0) return;
    const double local[3] = {q.x() - origin.x(), q.y() - origin.y(), q.z() - origin.z()};
    InclusiveRadiusSet set(r2, out);
    tree->findNeighbors(set, local, nanoflann::SearchParams());
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
      return a.second < b.second || (a.second == b.second && a.first < b.first);
    });
  }
};

namespace {
double checked_radius2(double radius) {
  if (!std::isfinite(radius) || radius < 0.0) {
    std::ostringstream msg;
    msg << "radius must be finite and >= 0, got " << radius;
    throw Error(ErrorCode::InvalidArgument, "radius", msg.str());
  }
  return radius * radius;
}
void check_k(int k) {
  if (k < 0) throw Error(ErrorCode::InvalidArgument, "k", "k must be >= 0, got " + std::to_string(k));
}
}  // namespace

KdTree::KdTree(const Points& points, KdTreeParams params)
    : impl_(std::make_unique<Impl>(points, nullptr, params)) {}
KdTree::KdTree(const Points& points, const IndexList& subset, KdTreeParams params)
    : impl_(std::make_unique<Impl>(points, &subset, params)) {}
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

Index KdTree::size() const { return static_cast<Index>(impl_->count()); }
const KdTreeParams& KdTree::params() const { return impl_->params; }

Index KdTree::nearest(const Vec3& q, double* dist2) const {
  check_query(q);
  std::uint32_t idx = 0;
  double d2 = std::numeric_limits<double>::infinity();
  if (impl_->knn_raw(q, 1, &idx, &d2) == 0) {
    if (dist2) *dist2 = std::numeric_limits<double>::infinity();
    return -1;
  }
  if (dist2) *dist2 = d2;
  return impl_->to_row(idx);
}

void KdTree::knn(const Vec3& q, int k, IndexList& indices, std::vector<double>& dist2) const {
  check_query(q);
  check_k(k);
  const std::size_t kk = std::min<std::size_t>(static_cast<std::size_t>(k), impl_->count());
  std::vector<std::uint32_t> idx(kk);
  dist2.resize(kk);
  const std::size_t found = impl_->knn_raw(q, kk, idx.data(), dist2.data());
  dist2.resize(found);
  indices.resize(found);
  for (std::size_t i = 0; i < found; ++i) indices[i] = impl_->to_row(idx[i]);
}

void KdTree::radius(const Vec3& q, double radius, IndexList& indices, std::vector<double>& dist2) const {
  check_query(q);
  const double r2 = checked_radius2(radius);
  std::vector<std::pair<std::uint32_t, double>> hits;
  impl_->radius_raw(q, r2, hits);
  indices.resize(hits.size());
  dist2.resize(hits.size());
  for (std::size_t i = 0; i < hits.size(); ++i) {
    indices[i] = impl_->to_row(hits[i].first);
    dist2[i] = hits[i].second;
  }
}

KnnResult KdTree::knn(const Points& queries, int k) const {
  check_k(k);
  require_finite(queries, "queries");
  const Eigen::Index nq = queries.rows();
  // The padded #Q by k result is allocated in full; refuse sizes beyond 2^28 entries (~3 GB).
  if (static_cast<double>(nq) * static_cast<double>(k) > static_cast<double>(1 << 28)) {
    throw Error(ErrorCode::TooLarge, "k",
                std::to_string(nq) + " queries x k = " + std::to_string(k) + " exceeds 2^28 result entries");
  }
  KnnResult result;
  result.indices.setConstant(nq, k, -1);
  result.dist2.setConstant(nq, k, std::numeric_limits<double>::infinity());
  const std::size_t kk = std::min<std::size_t>(static_cast<std::size_t>(k), impl_->count());
  if (kk == 0 || nq == 0) return result;
  const Impl& impl = *impl_;
#pragma omp parallel num_threads(resolve_threads(impl.params.threads))
  {
    std::vector<std::uint32_t> idx(kk);
#pragma omp for schedule(static)
    for (Eigen::Index q = 0; q < nq; ++q) {
      double* d2 = result.dist2.row(q).data();
      const std::size_t found = impl.knn_raw(queries.row(q).transpose(), kk, idx.data(), d2);
      for (std::size_t j = 0; j < found; ++j) result.indices(q, j) = impl.to_row(idx[j]);
      for (std::size_t j = found; j < static_cast<std::size_t>(k); ++j) {
        d2[j] = std::numeric_limits<double>::infinity();
      }
    }
  }
  return result;
}

RadiusResult KdTree::radius(const Points& queries, double radius) const {
  const double r2 = checked_radius2(radius);
  require_finite(queries, "queries");
  const Eigen::Index nq = queries.rows();
  RadiusResult result;
  result.offsets.assign(static_cast<std::size_t>(nq) + 1, 0);
  if (nq == 0) return result;
  const Impl& impl = *impl_;
  // Per-query hit lists, then a prefix sum into CSR form.
  std::vector<std::vector<std::pair<std::uint32_t, double>>> hits(static_cast<std::size_t>(nq));
#pragma omp parallel for schedule(dynamic, 64) num_threads(resolve_threads(impl.params.threads))
  for (Eigen::Index q = 0; q < nq; ++q) {
    impl.radius_raw(queries.row(q).transpose(), r2, hits[static_cast<std::size_t>(q)]);
  }
  for (Eigen::Index q = 0; q < nq; ++q) {
    result.offsets[q + 1] = result.offsets[q] + static_cast<std::int64_t>(hits[q].size());
  }
  result.indices.resize(static_cast<std::size_t>(result.offsets.back()));
  result.dist2.resize(result.indices.size());
#pragma omp parallel for schedule(static) num_threads(resolve_threads(impl.params.threads))
  for (Eigen::Index q = 0; q < nq; ++q) {
    std::size_t o = static_cast<std::size_t>(result.offsets[q]);
    for (const auto& h : hits[q]) {
      result.indices[o] = impl.to_row(h.first);
      result.dist2[o] = h.second;
      ++o;
    }
  }
  return result;
}

std::size_t KdTree::memory_bytes() const {
  const Impl& impl = *impl_;
  std::size_t bytes = sizeof(Impl) + impl.cloud.xyz.capacity() * sizeof(double) +
                      impl.rows.capacity() * sizeof(Index);
  if (impl.tree) bytes += sizeof(NanoTree) + impl.tree->usedMemory(*impl.tree);
  return bytes;
}

}  // namespace surfeledit
