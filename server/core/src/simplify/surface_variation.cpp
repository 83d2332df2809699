#include "surfeledit/core/simplify/surface_variation.hpp"
#include "surfeledit/core/util.hpp"

#include <Eigen/Eigenvalues>
#include <omp.h>

namespace surfeledit {

double Covariance::variation() const {
  const double sum = eigenvalues.sum();
  if (!(sum > 0.0)) return 0.0;
  return std::max(0.0, eigenvalues[0]) / sum;
}

Covariance covariance_of(const Points& positions, const Index* rows, std::size_t n) {
  Covariance c;
  c.count = static_cast<Index>(n);
  if (n == 0) return c;
  Vec3 sum = Vec3::Zero();
  for (std::size_t k = 0; k < n; ++k) sum += positions.row(rows[k]).transpose();
  c.centroid = sum / static_cast<double>(n);
  Mat3 m = Mat3::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 d = positions.row(rows[k]).transpose() - c.centroid;
    m.noalias() += d * d.transpose();
  }
  m /= static_cast<double>(n);
  // Iterative solver: Eigen documents computeDirect() as less accurate, and flat sets need l0 precisely.
  Eigen::SelfAdjointEigenSolver<Mat3> es(m);
  c.eigenvalues = es.eigenvalues();
  c.eigenvectors = es.eigenvectors();
  return c;
}

Values surface_variation(const Points& positions, const KdTree& tree, int k, const IndexList& rows, int threads) {
  if (k < 1) throw Error(ErrorCode::InvalidArgument, "k", "k must be >= 1, got " + std::to_string(k));
  const Index total = static_cast<Index>(positions.rows());
  IndexList all;
  const IndexList* list = &rows;
  if (rows.empty()) {
    all.resize(static_cast<std::size_t>(total));
    for (Index r = 0; r < total; ++r) all[r] = r;
    list = &all;
  }
  Values out = Values::Zero(total);
  const Index n = static_cast<Index>(list->size());
  const int t = resolve_threads(threads);
#pragma omp parallel num_threads(t)
  {
    IndexList nn;
    std::vector<double> dist2;
#pragma omp for schedule(dynamic, 256)
    for (Index q = 0; q < n; ++q) {
      const Index r = (*list)[q];
      tree.knn(positions.row(r).transpose(), k, nn, dist2);
      out[r] = surface_variation(positions, nn.data(), nn.size());
    }
  }
  return out;
}

}  // namespace surfeledit
