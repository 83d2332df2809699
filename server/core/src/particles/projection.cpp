// Tangent-plane and MLS projection onto the original samples (thesis §12.3.7).
#include "surfeledit/core/particles/projection.hpp"

#include <cmath>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {

SurfaceProjector::SurfaceProjector(const Points& positions, const Points& normals)
    : positions_(positions), normals_(normals) {
  if (positions.rows() == 0 || normals.rows() != positions.rows())
    throw Error(ErrorCode::InvalidArgument, "surface", "expected >= 1 sample and one normal per sample");
  require_finite(normals, "surface normals");
  KdTreeParams kp;
  kp.threads = 1;
  tree_ = std::make_unique<KdTree>(positions_, kp);
}

SurfaceProjector::~SurfaceProjector() = default;
SurfaceProjector::SurfaceProjector(SurfaceProjector&&) noexcept = default;
SurfaceProjector& SurfaceProjector::operator=(SurfaceProjector&&) noexcept = default;

Vec3 SurfaceProjector::onto_tangent_plane(const Vec3& x) const {
  const Index k = tree_->nearest(x);
  const Vec3 p = positions_.row(k).transpose(), nk = normals_.row(k).transpose();
  return x - (x - p).dot(nk) * nk;
}

Vec3 SurfaceProjector::onto_mls(const Vec3& x0, double h, Vec3* normal) const {
  Vec3 x = x0;
  IndexList idx;
  std::vector<double> dist2;
  for (int it = 0; it < 50; ++it) {
    tree_->radius(x, 3.0 * h, idx, dist2);
    if (idx.empty()) return x;
    Vec3 c = Vec3::Zero(), nrm = Vec3::Zero();
    double wsum = 0.0;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const double wk = std::exp(-dist2[k] / (h * h));
      c += wk * positions_.row(idx[k]).transpose();
      nrm += wk * normals_.row(idx[k]).transpose();
      wsum += wk;
    }
    c /= wsum;
    if (nrm.norm() == 0.0) return x;
    nrm.normalize();
    const Vec3 next = x0 - (x0 - c).dot(nrm) * nrm;  // x0 onto the plane fitted around the current point
    if (normal) *normal = nrm;
    const bool done = (next - x).norm() < 1e-9 * h;
    x = next;
    if (done) break;
  }
  return x;
}

}  // namespace surfeledit
