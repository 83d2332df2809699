// k-d tree over 3-D points for kNN and radius queries (docs/algorithms.md §3).
//
// The tree keeps its own copy of the points in a local frame (relative to their
// centroid) so that precision does not depend on where the model sits in space,
// stored in leaf order (each leaf one contiguous run). Results are exact (eps = 0);
// among points at equal distance the one stored first in the tree wins, so batch and
// single queries return the same rows whatever the thread count or query order.
// Results are row indices into the point array it was built from (or, when built
// over a subset, into that same full array).
#pragma once

#include <memory>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

// How a leaf's points are scanned. Every scan gives the same bits (the same operations per point, no fused
// multiply-adds), so the choice changes speed only; tests and benchmarks pin one to compare.
enum class KdScan : std::uint8_t {
  Auto = 0,    // the widest this CPU has
  Scalar = 1,  // one point at a time (any CPU)
  Avx2 = 2,    // four points at a time (CPUs with AVX2)
  Avx512 = 3,  // the AVX2 scan's source built for AVX-512 (CPUs with AVX-512F, VL and DQ): eight points and a fan's
               // eight cells per vector, the same operations per lane (RESULTS §73)
};
// Whether `scan` can run on this CPU and build (Auto and Scalar always can).
bool kd_scan_available(KdScan scan);

struct KdTreeParams {
  int leaf_size = 10;  // max points per leaf ("bucket size"; the thesis found ~10 best for small k)
  int threads = 0;     // worker threads for batch queries; 0 = all hardware threads
  double eps = 0.0;    // approximate kNN / nearest (eps >= 0): a returned neighbour's squared
                       // distance is at most (1 + eps) x that of the true one; 0 = exact. Radius queries stay exact.
  KdScan scan = KdScan::Auto;  // leaf scan; one this CPU lacks throws InvalidArgument at construction
  bool frames = false;  // keep an oriented box per node where it is much thinner than the points' axis-aligned box
                        // (4 B per node, 60 B per box kept): exact k = 1 searches then skip more of a surface tilted
                        // against the axes
  bool align = false;   // build and search in a frame turned along the points' surfaces (from a sample: the axes along
                        // which its coordinates concentrate), when their box in it has under 0.7 of the axis-aligned
                        // box's volume (a model tilted as a whole); distances then round differently (~1e-16 of the
                        // model's size) and ties within that may go either way. An upright model is not turned
  bool cells = false;  // keep what nearest_from() needs to start at a leaf: with the AVX2 scan fans (about 0.3 per
                       // leaf: 40 B and 112 B per four cells), 4 B per node and the fans' halos (36 B per fan and 10 B
                       // per node of a halo, about 5 per leaf), else each node's cell (28 B per node)
};

// kNN result for #Q queries: #Q by k, row-major. Rows with fewer than k hits
// (fewer points than k) are padded with index -1 and dist2 = +inf.
struct KnnResult {
  Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> indices;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dist2;  // squared distances
};

// Radius result for #Q queries in CSR form: hits of query q are
// indices[offsets[q] .. offsets[q+1]), sorted by increasing dist2.
struct RadiusResult {
  std::vector<std::int64_t> offsets;  // #Q + 1
  IndexList indices;
  std::vector<double> dist2;  // squared distances
};

class KdTree {
 public:
  // Builds over all rows of `points` (#P by 3). Throws InvalidArgument on non-finite input.
  explicit KdTree(const Points& points, KdTreeParams params = {});
  // Builds over the rows listed in `subset` only; results still index rows of `points`.
  KdTree(const Points& points, const IndexList& subset, KdTreeParams params = {});
  ~KdTree();
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;

  Index size() const;  // number of points in the tree
  const KdTreeParams& params() const;
  // The tree's local axes in world coordinates, as rows: the identity unless `align` turned them.
  Mat3 axes() const;

  // Nearest point to q; returns -1 when the tree is empty. `dist2` gets the squared distance.
  Index nearest(const Vec3& q, double* dist2 = nullptr) const;
  // Nearest point to q among those with dist2 <= max_dist2 (inclusive); -1 (dist2 = +inf) when there is
  // none. A warm start: a caller that knows some point at squared distance D from q (e.g. the previous
  // step's nearest) passes D and gets the same answer as nearest(q), with less of the tree visited.
  // Throws InvalidArgument for a NaN or negative max_dist2.
  Index nearest_within(const Vec3& q, double max_dist2, double* dist2 = nullptr) const;
  // nearest(q), searched from a leaf up (for a caller whose queries move little between calls): `leaf` is a leaf
  // to start from, in (any value: a stale, wrong or unset one costs time, never exactness; pass the value a
  // previous call left; one that is not a leaf starts at the leaf the descent reaches first), and the leaf
  // holding the answer, out (unchanged when there is none). The same row and dist2 as nearest(q), ties included. A tree without `cells` answers by the root descent (and still sets
  // `leaf`); one with eps > 0 answers nearest(q) and leaves `leaf` as it was.
  Index nearest_from(const Vec3& q, std::uint32_t& leaf, double* dist2 = nullptr) const;
  // k nearest to q (fewer if the tree holds fewer), ascending by distance.
  void knn(const Vec3& q, int k, IndexList& indices, std::vector<double>& dist2) const;
  // All points within real distance `radius` (inclusive) of q, ascending by distance.
  void radius(const Vec3& q, double radius, IndexList& indices, std::vector<double>& dist2) const;
  // How many points have a squared distance from q below `max_dist2` (strictly), counting no further than `limit`
  // (the search stops there, so a count that reaches it costs about one leaf). Throws InvalidArgument for a NaN or
  // negative max_dist2 or a negative limit.
  Index count_within(const Vec3& q, double max_dist2, Index limit) const;

  // Batch versions, multithreaded over queries (`params().threads`; knn: `threads` when > 0); thread-safe, const.
  // The queries are answered in Morton-curve order when the tree holds >= 2^16 points (cache reuse), and written
  // back in the caller's order.
  KnnResult knn(const Points& queries, int k, int threads = 0) const;
  RadiusResult radius(const Points& queries, double radius) const;

  // Bytes held by the tree (points copy 24 B and row map 4 B per point, nodes 16 B each, cells 28 B each).
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace surfeledit
