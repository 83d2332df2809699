// k-d tree over 3-D points (docs/algorithms.md §3): API, input checks and batches. The build (Morton sort,
// midpoint cuts, leaf order) is in kdtree_build.cpp, the exact descent in kdtree_search.hpp, the search from
// a leaf in kdtree_walk.hpp; batches on large trees are answered along a Morton curve, each query warm-started
// from the previous answer.
#include "surfeledit/core/kdtree.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "kdtree_walk.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

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

double checked_radius2(double radius) {
  if (!std::isfinite(radius) || radius < 0.0) {
    std::ostringstream msg;
    msg << "radius must be finite and >= 0, got " << radius;
    throw Error(ErrorCode::InvalidArgument, "radius", msg.str());
  }
  return radius * radius;
}

// A squared-distance bound: >= 0, +inf allowed (every point).
void check_max_dist2(double max_dist2) {
  if (std::isnan(max_dist2) || max_dist2 < 0.0) {
    throw Error(ErrorCode::InvalidArgument, "max_dist2", "must be >= 0 (or +inf), got " + std::to_string(max_dist2));
  }
}

const kd::SearchFns* search_for(KdScan scan) {
  static const kd::SearchFns scalar = kd::search_fns<kd::ScalarScan, kd::ScalarWalk>();
  switch (scan) {
    case KdScan::Auto:
      if (kd_scan_available(KdScan::Avx512)) return kd::avx512_search();
      return kd_scan_available(KdScan::Avx2) ? kd::avx2_search() : &scalar;
    case KdScan::Scalar:
      return &scalar;
    case KdScan::Avx2:
      if (kd_scan_available(scan)) return kd::avx2_search();
      break;
    case KdScan::Avx512:
      if (kd_scan_available(scan)) return kd::avx512_search();
      break;
  }
  throw Error(ErrorCode::InvalidArgument, "scan",
              "leaf scan " + std::to_string(static_cast<int>(scan)) + " is not available on this CPU or build");
}

void check_k(int k) {
  if (k < 0) throw Error(ErrorCode::InvalidArgument, "k", "k must be >= 0, got " + std::to_string(k));
}

}  // namespace

void kd::RadiusSet::push(std::uint32_t s, double d2) { out->emplace_back(s, d2); }

bool kd_scan_available(KdScan scan) {
  switch (scan) {
    case KdScan::Auto:
    case KdScan::Scalar:
      return true;
    case KdScan::Avx2:
      return kd::avx2_search() != nullptr && __builtin_cpu_supports("avx2");
    case KdScan::Avx512:
      return kd::avx512_search() != nullptr && __builtin_cpu_supports("avx512f") &&
             __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq");
  }
  return false;
}

// Trees of at least this many points (about 2 MB of points and nodes, a core's L2 here) answer batches
// along a Morton curve.
constexpr std::size_t kCurveMinPoints = 1 << 16;

struct KdTree::Impl {
  KdTreeParams params;
  Vec3 origin = Vec3::Zero();  // centroid of the tree's points, world units
  bool turned = false;         // the local frame is turned (KdTreeParams::align)
  double turn[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  // rows: the local frame's axes in world coordinates
  kd::Tree tree;
  const kd::SearchFns* search = nullptr;  // the descent with params.scan's leaf scan

  Impl(const Points& points, const IndexList* subset, KdTreeParams p) : params(p) {
    check_params(params);
    search = search_for(params.scan);
    const Eigen::Index n_all = points.rows();
    if (n_all > static_cast<Eigen::Index>(std::numeric_limits<Index>::max())) {
      throw Error(ErrorCode::TooLarge, "points", "too many points: " + std::to_string(n_all));
    }
    if (subset) {
      for (std::size_t i = 0; i < subset->size(); ++i) {
        const Index r = (*subset)[i];
        if (r < 0 || r >= n_all) {
          std::ostringstream msg;
          msg << "subset entry " << i << " = " << r << " is out of range [0, " << n_all << ")";
          throw Error(ErrorCode::InvalidArgument, "subset", msg.str());
        }
      }
    }
    const std::size_t n = subset ? subset->size() : static_cast<std::size_t>(n_all);
    if (n == 0) return;
    std::vector<std::uint32_t> rows(n);
    for (std::size_t i = 0; i < n; ++i) rows[i] = static_cast<std::uint32_t>(subset ? (*subset)[i] : static_cast<Index>(i));
    // One pass: centroid by a shifted mean (relative to the first point, for precision far from the origin)
    // and bounding box; a non-finite point makes them non-finite and is then located for the message.
    const double* P = points.data();
    const double* ref = P + 3 * static_cast<std::size_t>(rows[0]);
    double sum[3] = {0, 0, 0}, lo[3], hi[3];
    std::copy_n(ref, 3, lo);
    std::copy_n(ref, 3, hi);
    for (const std::uint32_t r : rows) {
      const double* p = P + 3 * static_cast<std::size_t>(r);
      for (int d = 0; d < 3; ++d) {
        sum[d] += p[d] - ref[d];
        lo[d] = std::min(lo[d], p[d]);
        hi[d] = std::max(hi[d], p[d]);
      }
    }
    if (!std::isfinite(sum[0] + sum[1] + sum[2] + lo[0] + lo[1] + lo[2] + hi[0] + hi[1] + hi[2])) {
      for (const std::uint32_t r : rows) {
        if (!points.row(r).allFinite()) {
          throw Error(ErrorCode::InvalidArgument, "points", "non-finite point at row " + std::to_string(r));
        }
      }
      throw Error(ErrorCode::InvalidArgument, "points", "coordinates overflow (sum of offsets is not finite)");
    }
    for (int d = 0; d < 3; ++d) {
      origin[d] = ref[d] + sum[d] / static_cast<double>(n);
      lo[d] -= origin[d];  // subtracting a constant is monotonic: these are the local box's corners exactly
      hi[d] -= origin[d];
    }
    // A turned frame (KdTreeParams::align): every point turned, numbered 0 .. n - 1 in `rows`' order, and the tree
    // given the rows they stand for after its build; kept when their box is clearly smaller than the axis-aligned one.
    double candidate[3][3];
    std::vector<double> local_points;
    if (params.align && kd::choose_turn(P, rows, origin.data(), candidate)) {
      local_points.resize(3 * n);
      double tlo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, thi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
      for (std::size_t i = 0; i < n; ++i) {
        double* x = local_points.data() + 3 * i;
        turn_local(candidate, points.row(rows[i]).transpose(), x);
        for (int d = 0; d < 3; ++d) {
          tlo[d] = std::min(tlo[d], x[d]);
          thi[d] = std::max(thi[d], x[d]);
        }
      }
      if (kd::floored_volume(tlo, thi) < kd::kTurnedVolume * kd::floored_volume(lo, hi)) {
        turned = true;
        std::copy_n(&candidate[0][0], 9, &turn[0][0]);
        std::copy_n(tlo, 3, lo);
        std::copy_n(thi, 3, hi);
      }
    }
    if (turned) {
      std::vector<std::uint32_t> seq(n);
      for (std::size_t i = 0; i < n; ++i) seq[i] = static_cast<std::uint32_t>(i);
      const double zero[3] = {0.0, 0.0, 0.0};
      kd::build(tree, local_points.data(), std::move(seq), zero, lo, hi, static_cast<std::uint32_t>(params.leaf_size));
      for (std::uint32_t& r : tree.rows) r = rows[r];
    } else {
      kd::build(tree, P, std::move(rows), origin.data(), lo, hi, static_cast<std::uint32_t>(params.leaf_size));
    }
    if (params.frames) kd::build_frames(tree);
    if (params.cells) {
      kd::build_cells(tree);
      if (search->fans) kd::build_fans(tree);
    }
  }

  double eps_factor() const { return 1.0 + params.eps; }
  // Where q is in the tree's frame: relative to the origin, and turned when the tree is.
  void local(const Vec3& q, double* out) const {
    if (!turned) {
      for (int d = 0; d < 3; ++d) out[d] = q[d] - origin[d];
      return;
    }
    turn_local(turn, q, out);
  }
  // q relative to the origin, turned by `r` (rows: the axes). The points of a turned tree went through this same
  // function, so a query at a point's place is at that point's local place exactly.
  void turn_local(const double (&r)[3][3], const Vec3& q, double* out) const {
    const double t[3] = {q[0] - origin[0], q[1] - origin[1], q[2] - origin[2]};
    for (int k = 0; k < 3; ++k) out[k] = r[k][0] * t[0] + r[k][1] * t[1] + r[k][2] * t[2];
  }

  // The order a batch is answered in: along the curve for a tree larger than the caches (scene 300k,
  // random order: 2x faster), else the caller's (bunny 35k: the scattered reads and writes of a curve
  // order cost 25% more than the tree's cache misses they save; RESULTS §16.1).
  std::vector<std::uint32_t> order_for(const Points& queries) const {
    if (tree.size() >= kCurveMinPoints) return curve_order(queries);
    std::vector<std::uint32_t> order(static_cast<std::size_t>(queries.rows()));
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
    return order;
  }

  // Queries' order along a Morton curve over the tree's box (10 bits per axis), by a 3-pass radix sort.
  std::vector<std::uint32_t> curve_order(const Points& queries) const {
    const std::size_t nq = static_cast<std::size_t>(queries.rows());
    double scale[3];
    for (int d = 0; d < 3; ++d) {
      const double ext = tree.box_hi[d] - tree.box_lo[d];
      scale[d] = ext > 0.0 ? 1023.0 / ext : 0.0;
    }
    std::vector<std::uint32_t> code(nq), order(nq);
    for (std::size_t i = 0; i < nq; ++i) {
      std::uint32_t c = 0;
      double lq[3];
      local(queries.row(static_cast<Eigen::Index>(i)).transpose(), lq);
      for (int d = 0; d < 3; ++d) {
        const double x = (lq[d] - tree.box_lo[d]) * scale[d];
        c |= kd::spread10(static_cast<std::uint32_t>(std::clamp(x, 0.0, 1023.0))) << d;
      }
      code[i] = c;
      order[i] = static_cast<std::uint32_t>(i);
    }
    kd::radix_sort(code, order);
    return order;
  }
};

KdTree::KdTree(const Points& points, KdTreeParams params)
    : impl_(std::make_unique<Impl>(points, nullptr, params)) {}
KdTree::KdTree(const Points& points, const IndexList& subset, KdTreeParams params)
    : impl_(std::make_unique<Impl>(points, &subset, params)) {}
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

Index KdTree::size() const { return static_cast<Index>(impl_->tree.size()); }
const KdTreeParams& KdTree::params() const { return impl_->params; }
Mat3 KdTree::axes() const {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int d = 0; d < 3; ++d) r(i, d) = impl_->turn[i][d];
  return r;
}

Index KdTree::nearest(const Vec3& q, double* dist2) const {
  return nearest_within(q, std::numeric_limits<double>::infinity(), dist2);
}

Index KdTree::nearest_within(const Vec3& q, double max_dist2, double* dist2) const {
  check_query(q);
  check_max_dist2(max_dist2);
  const Impl& impl = *impl_;
  double x[3];
  impl.local(q, x);
  kd::NearestSet set(max_dist2);
  impl.search->nearest(impl.tree, x, set, impl.eps_factor());
  if (dist2) *dist2 = set.slot == kd::NearestSet::kNone ? std::numeric_limits<double>::infinity() : set.best;
  return set.slot == kd::NearestSet::kNone ? -1 : static_cast<Index>(impl.tree.rows[set.slot]);
}

Index KdTree::nearest_from(const Vec3& q, std::uint32_t& leaf, double* dist2) const {
  const Impl& impl = *impl_;
  if (impl.params.eps != 0.0) return nearest(q, dist2);
  check_query(q);
  double x[3];
  impl.local(q, x);
  kd::NearestSet set;
  impl.search->nearest_from(impl.tree, x, set, leaf);
  if (dist2) *dist2 = set.slot == kd::NearestSet::kNone ? std::numeric_limits<double>::infinity() : set.best;
  return set.slot == kd::NearestSet::kNone ? -1 : static_cast<Index>(impl.tree.rows[set.slot]);
}

Index KdTree::count_within(const Vec3& q, double max_dist2, Index limit) const {
  check_query(q);
  check_max_dist2(max_dist2);
  if (limit < 0) throw Error(ErrorCode::InvalidArgument, "limit", "must be >= 0, got " + std::to_string(limit));
  const Impl& impl = *impl_;
  double x[3];
  impl.local(q, x);
  kd::CountSet set{max_dist2, static_cast<std::size_t>(limit)};
  if (limit > 0) impl.search->count(impl.tree, x, set, 1.0);
  return static_cast<Index>(set.n);
}

void KdTree::knn(const Vec3& q, int k, IndexList& indices, std::vector<double>& dist2) const {
  check_query(q);
  check_k(k);
  const Impl& impl = *impl_;
  const std::size_t kk = std::min<std::size_t>(static_cast<std::size_t>(k), impl.tree.size());
  std::vector<std::uint32_t> slots(kk);
  dist2.resize(kk);
  double x[3];
  impl.local(q, x);
  kd::KnnSet set(kk, slots.data(), dist2.data());
  if (kk > 0) impl.search->knn(impl.tree, x, set, impl.eps_factor());
  dist2.resize(set.size());
  indices.resize(set.size());
  for (std::size_t i = 0; i < set.size(); ++i) indices[i] = static_cast<Index>(impl.tree.rows[slots[i]]);
}

void KdTree::radius(const Vec3& q, double radius, IndexList& indices, std::vector<double>& dist2) const {
  check_query(q);
  const double r2 = checked_radius2(radius);
  const Impl& impl = *impl_;
  std::vector<std::pair<std::uint32_t, double>> hits;
  double x[3];
  impl.local(q, x);
  kd::RadiusSet set{r2, &hits};
  impl.search->radius(impl.tree, x, set, 1.0);
  std::sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) {
    return a.second < b.second || (a.second == b.second && a.first < b.first);
  });
  indices.resize(hits.size());
  dist2.resize(hits.size());
  for (std::size_t i = 0; i < hits.size(); ++i) {
    indices[i] = static_cast<Index>(impl.tree.rows[hits[i].first]);
    dist2[i] = hits[i].second;
  }
}

KnnResult KdTree::knn(const Points& queries, int k, int threads) const {
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
  const Impl& impl = *impl_;
  const std::size_t kk = std::min<std::size_t>(static_cast<std::size_t>(k), impl.tree.size());
  if (kk == 0 || nq == 0) return result;
  // Answered along a Morton curve for large trees (neighbouring queries reuse cached nodes and leaves),
  // written back in the caller's order. Exact search starts from the previous query's answer: its distances to this
  // query bound the answer from above, and the tie rule makes the result independent of that start.
  const std::vector<std::uint32_t> order = impl.order_for(queries);
  const bool warm = impl.params.eps == 0.0;
  const double eps_factor = impl.eps_factor();
#pragma omp parallel num_threads(resolve_threads(threads > 0 ? threads : impl.params.threads))
  {
    std::vector<std::uint32_t> slots(kk), prev(kk);
    std::size_t n_prev = 0;
#pragma omp for schedule(static)
    for (Eigen::Index i = 0; i < nq; ++i) {
      const Eigen::Index q = order[static_cast<std::size_t>(i)];
      double x[3];
      impl.local(queries.row(q).transpose(), x);
      double* d2 = result.dist2.row(q).data();
      double bound = std::numeric_limits<double>::infinity();
      std::size_t found;
      if (kk == 1) {
        kd::NearestSet set;
        if (warm && n_prev == 1) set.add(impl.tree.dist2(x, prev[0]), prev[0]);
        impl.search->nearest(impl.tree, x, set, eps_factor);
        found = set.slot == kd::NearestSet::kNone ? 0 : 1;
        slots[0] = set.slot;
        d2[0] = set.best;
      } else {
        if (warm && n_prev == kk) {
          bound = 0.0;
          for (std::size_t j = 0; j < kk; ++j) bound = std::max(bound, impl.tree.dist2(x, prev[j]));
        }
        kd::KnnSet set(kk, slots.data(), d2, bound);
        impl.search->knn(impl.tree, x, set, eps_factor);
        found = set.size();
      }
      for (std::size_t j = 0; j < found; ++j) result.indices(q, j) = static_cast<Index>(impl.tree.rows[slots[j]]);
      for (std::size_t j = found; j < static_cast<std::size_t>(k); ++j) d2[j] = std::numeric_limits<double>::infinity();
      std::copy(slots.begin(), slots.begin() + static_cast<std::ptrdiff_t>(found), prev.begin());
      n_prev = found;
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
  const std::vector<std::uint32_t> order = impl.order_for(queries);
  // Per-query hit lists (answered along the curve), then a prefix sum into CSR form.
  std::vector<std::vector<std::pair<std::uint32_t, double>>> hits(static_cast<std::size_t>(nq));
#pragma omp parallel for schedule(dynamic, 64) num_threads(resolve_threads(impl.params.threads))
  for (Eigen::Index i = 0; i < nq; ++i) {
    const std::uint32_t q = order[static_cast<std::size_t>(i)];
    double x[3];
    impl.local(queries.row(q).transpose(), x);
    auto& h = hits[q];
    kd::RadiusSet set{r2, &h};
    impl.search->radius(impl.tree, x, set, 1.0);
    std::sort(h.begin(), h.end(), [](const auto& a, const auto& b) {
      return a.second < b.second || (a.second == b.second && a.first < b.first);
    });
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
      result.indices[o] = static_cast<Index>(impl.tree.rows[h.first]);
      result.dist2[o] = h.second;
      ++o;
    }
  }
  return result;
}

std::size_t KdTree::memory_bytes() const {
  const kd::Tree& t = impl_->tree;
  return sizeof(Impl) + t.coords.capacity() * sizeof(double) + t.rows.capacity() * sizeof(std::uint32_t) +
         t.nodes.capacity() * sizeof(kd::Node) + t.cells.capacity() * sizeof(kd::Cell) +
         t.fans.capacity() * sizeof(kd::Fan) + t.fan_blocks.capacity() * sizeof(kd::FanBlock) +
         t.fan_of.capacity() * sizeof(std::uint32_t) + t.frames.capacity() * sizeof(kd::NodeFrame) +
         t.frame_of.capacity() * sizeof(std::uint32_t) + t.halos.capacity() * sizeof(kd::Halo) +
         t.halo_blocks.capacity() * sizeof(kd::HaloBlock);
}

}  // namespace surfeledit
