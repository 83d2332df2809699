// Tangent-plane and MLS projection onto the original samples (thesis §12.3.7).
#include "surfeledit/core/particles/projection.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <cmath>

#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

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
  Vec3 x = x0, nrm = Vec3::Zero();
  // One range query about x0 with a margin of h serves every foot point within h of x0 (the samples within
  // 3 h of the foot point are among them); a foot point farther away queries again about itself.
  IndexList found, idx;
  std::vector<double> found_d2, dist2;
  Vec3 centre = x0;
  const double margin = h, r2 = 9.0 * h * h;
  tree_->radius(centre, 3.0 * h + margin, found, found_d2);
  const auto near = [&](const Vec3& at) {
    if ((at - centre).norm() > margin) {
      centre = at;
      tree_->radius(centre, 3.0 * h + margin, found, found_d2);
    }
    idx.clear();
    dist2.clear();
    for (Index k : found) {
      const double d2 = (positions_.row(k).transpose() - at).squaredNorm();
      if (d2 <= r2) idx.push_back(k), dist2.push_back(d2);
    }
  };
  // The reference plane: a weighted plane about the foot point, iterated to a fixed point.
  for (int it = 0; it < 50; ++it) {
    near(x);
    if (idx.empty()) return x;
    Vec3 c = Vec3::Zero(), m = Vec3::Zero();
    double wsum = 0.0;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const double wk = std::exp(-dist2[k] / (h * h));
      c += wk * positions_.row(idx[k]).transpose();
      m += wk * normals_.row(idx[k]).transpose();
      wsum += wk;
    }
    c /= wsum;
    if (m.norm() == 0.0) return x;
    nrm = m.normalized();
    const Vec3 next = x0 - (x0 - c).dot(nrm) * nrm;  // x0 onto the plane fitted around the current point
    const bool done = (next - x).norm() < 1e-9 * h;
    x = next;
    if (done) break;
  }
  if (normal) *normal = nrm;
  // The quadratic height z = a0 + a1 u + a2 v + a3 u^2 + a4 u v + a5 v^2 over the plane, about the foot x
  // (coordinates in units of h), by weighted least squares; the surface point is x + a0 n.
  near(x);
  if (idx.size() < 6) return x;
  const Vec3 e1 = nrm.unitOrthogonal(), e2 = nrm.cross(e1);
  Eigen::Matrix<double, 6, 6> ata = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> atb = Eigen::Matrix<double, 6, 1>::Zero();
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const Vec3 d = (positions_.row(idx[k]).transpose() - x) / h;
    const double u = d.dot(e1), v = d.dot(e2), z = d.dot(nrm);
    const double wk = std::exp(-dist2[k] / (h * h));
    Eigen::Matrix<double, 6, 1> row;
    row << 1.0, u, v, u * u, u * v, v * v;
    ata.noalias() += wk * row * row.transpose();
    atb.noalias() += wk * z * row;
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(ata);
  const Eigen::Matrix<double, 6, 1> a = ldlt.solve(atb);
  // Singular (samples on a line or a conic): keep the plane. The diagonal ratio rejects near-singular fits.
  const Eigen::Matrix<double, 6, 1> dd = ldlt.vectorD();
  if (ldlt.info() != Eigen::Success || !a.allFinite() || dd.minCoeff() <= 1e-10 * dd.maxCoeff()) return x;
  if (std::abs(a[0]) > 3.0) return x;  // a height beyond the kernel: not a fit of this surface
  if (normal) *normal = (nrm - a[1] * e1 - a[2] * e2).normalized();
  return x + a[0] * h * nrm;
}

void project_rows_mls(const SurfaceProjector& surface, double h, Points& x, Points& normals, int threads) {
  if (normals.rows() != x.rows()) throw Error(ErrorCode::InvalidArgument, "normals", "expected one normal per row");
  const Eigen::Index n = x.rows();
  const int t = resolve_threads(threads);
#pragma omp parallel for num_threads(t) schedule(static) if (t > 1 && n > 2000)
  for (Eigen::Index i = 0; i < n; ++i) {
    Vec3 nrm = normals.row(i).transpose();
    const Vec3 p = surface.onto_mls(x.row(i).transpose(), h, &nrm);
    x.row(i) = p.transpose();
    normals.row(i) = nrm.transpose();
  }
}

}  // namespace surfeledit
