// Inside/outside test (docs/algorithms.md §2): nearest surfel (p2, n2) of the query p1; inside iff
// (p1 - p2) . n2 <= W.
#include "surfeledit/core/inside_outside.hpp"
#include "surfeledit/core/util.hpp"

#include <omp.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace surfeledit {

namespace {

const Points& checked_normals(const Points& positions, const Points& normals) {
  if (normals.rows() != positions.rows()) {
    std::ostringstream msg;
    msg << "normals have " << normals.rows() << " rows but positions have " << positions.rows();
    throw Error(ErrorCode::InvalidArgument, "normals", msg.str());
  }
  require_finite(normals, "normals");
  return normals;
}

void check_threshold(double w) {
  if (!std::isfinite(w)) {
    std::ostringstream msg;
    msg << "threshold must be finite, got " << w;
    throw Error(ErrorCode::InvalidArgument, "threshold", msg.str());
  }
}

}  // namespace

InsideOutside::InsideOutside(const Points& positions, const Points& normals, KdTreeParams tree)
    : normals_(checked_normals(positions, normals)), tree_(positions, tree), positions_(positions) {}

bool InsideOutside::inside(const Vec3& q, double threshold, Index* nearest, double* signed_offset) const {
  check_threshold(threshold);
  const Index i = tree_.nearest(q);
  if (nearest) *nearest = i;
  if (i < 0) {  // empty model: nothing is inside
    if (signed_offset) *signed_offset = std::numeric_limits<double>::infinity();
    return false;
  }
  // (p1 - p2) . n2, model units (a signed distance along the surfel normal, not squared).
  const double offset = (q - positions_.row(i).transpose()).dot(normals_.row(i).transpose());
  if (signed_offset) *signed_offset = offset;
  return offset <= threshold;
}

std::vector<std::uint8_t> InsideOutside::classify(const Points& queries, InsideOutsideParams params) const {
  check_threshold(params.threshold);
  if (params.threads < 0) {
    throw Error(ErrorCode::InvalidArgument, "threads",
                "thread count must be >= 0, got " + std::to_string(params.threads));
  }
  require_finite(queries, "queries");
  const Eigen::Index nq = queries.rows();
  std::vector<std::uint8_t> flags(static_cast<std::size_t>(nq), 0);
  if (nq == 0 || tree_.size() == 0) return flags;
  const int threads = resolve_threads(params.threads);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (Eigen::Index q = 0; q < nq; ++q) {
    const Vec3 p1 = queries.row(q).transpose();
    const Index i = tree_.nearest(p1);
    const double offset = (p1 - positions_.row(i).transpose()).dot(normals_.row(i).transpose());
    flags[static_cast<std::size_t>(q)] = offset <= params.threshold ? 1 : 0;
  }
  return flags;
}

const KdTree& InsideOutside::tree() const { return tree_; }

std::vector<std::uint8_t> classify_inside(const Points& positions, const Points& normals,
                                          const Points& queries, InsideOutsideParams params) {
  KdTreeParams tree;
  tree.threads = params.threads;
  return InsideOutside(positions, normals, tree).classify(queries, params);
}

}  // namespace surfeledit
