// The k-d tree's oriented node boxes (KdTreeParams::frames, kdtree_search.hpp's NodeFrame): built bottom-up from
// the points' moments, with half extents that bound every point's exact projection on the stored float axes.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Eigenvalues>

#include "kdtree_search.hpp"

namespace surfeledit::kd {

// Each node's principal axes (eigenvectors of its points' covariance) and centroid, rounded to float, and per axis a
// half extent that bounds every point's exact projection on the stored axes. Bottom-up (reverse pre-order), so the
// build stays linear: a leaf's moments and box from its points, its half extents from its points' projections
// (computed with the float axes, plus the product's rounding error, a few ulps of |p - c|: 2e-15 of its 1-norm,
// rounded up to a float); an inner node's moments and box as its children's sums, its half extents from each child's
// 8 box corners or 8 oriented-box corners, whichever bounds the child tighter on that axis (an oriented box holds
// its points only up to its float axes' error, ~1e-7 of its size: 1e-6 of the sum of its half extents is added, and
// its corners' rounding).
// Kept (in t.frames, its index in t.frame_of; an inner node kept gets kFramed in Node::b) where the thinnest half extent is under kThinner of the thinnest half side of the points'
// axis-aligned box: the surface is tilted against the axes there.
void build_frames(Tree& t) {
  constexpr double kThinner = 0.5;
  const std::size_t n = t.nodes.size();
  struct Sums {
    double count = 0.0;
    Eigen::Vector3d s = Eigen::Vector3d::Zero(), lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();  // sum of p p^T
  };
  std::vector<Sums> sums(n);
  std::vector<NodeFrame> frame(n);  // every node's frame, kept or not (its parent reads its corners)
  t.frame_of.assign(n, Tree::kNoFrame);
  std::vector<std::uint32_t> kept;  // nodes that keep theirs, bottom-up
  // The 8 corners of the box centre c +- half along the three axes (rows of `axis`), in doubles.
  auto corners = [](const double* c, const double (*axis)[3], const double* half, Eigen::Vector3d* out) {
    for (int k = 0; k < 8; ++k)
      for (int d = 0; d < 3; ++d)
        out[k][d] = c[d] + ((k & 1) ? half[0] : -half[0]) * axis[0][d] + ((k & 2) ? half[1] : -half[1]) * axis[1][d] +
                    ((k & 4) ? half[2] : -half[2]) * axis[2][d];
  };
  for (std::size_t i = n; i-- > 0;) {
    const Node& nd = t.nodes[i];
    Sums& z = sums[i];
    if (nd.leaf()) {
      double sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
      for (std::uint32_t s = nd.a; s < nd.b; ++s) {
        const double x = t.xs()[s], y = t.ys()[s], w = t.zs()[s];
        sx += x, sy += y, sz += w;
        xx += x * x, xy += x * y, xz += x * w, yy += y * y, yz += y * w, zz += w * w;
        z.lo = z.lo.cwiseMin(Eigen::Vector3d(x, y, w));
        z.hi = z.hi.cwiseMax(Eigen::Vector3d(x, y, w));
      }
      z.count = static_cast<double>(nd.b - nd.a);
      z.s = Eigen::Vector3d(sx, sy, sz);
      z.m << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    } else {
      const Sums &l = sums[i + 1], &r = sums[nd.a];
      z.count = l.count + r.count;
      z.s = l.s + r.s;
      z.m = l.m + r.m;
      z.lo = l.lo.cwiseMin(r.lo);
      z.hi = l.hi.cwiseMax(r.hi);
    }
    NodeFrame& g = frame[i];
    g.half[0] = std::numeric_limits<float>::quiet_NaN();
    if (z.count < 2.0) continue;
    const Eigen::Vector3d mean = z.s / z.count;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(z.m / z.count - mean * mean.transpose());
    double c[3], axis[3][3], half[3];
    for (int d = 0; d < 3; ++d) {
      g.c[d] = static_cast<float>(mean[d]);
      c[d] = static_cast<double>(g.c[d]);
      for (int k = 0; k < 3; ++k) {
        g.axis[k][d] = static_cast<float>(eig.eigenvectors()(d, k));
        axis[k][d] = static_cast<double>(g.axis[k][d]);
      }
    }
    // Widens reach[0..2] to p's projections on the three axes, each plus its rounding error (2e-15 of |p - c|_1).
    auto reach_of = [&](double x, double y, double w, double* reach) {
      const double d[3] = {x - c[0], y - c[1], w - c[2]};
      const double err = 2e-15 * (std::abs(d[0]) + std::abs(d[1]) + std::abs(d[2]));
      for (int k = 0; k < 3; ++k)
        reach[k] = std::max(reach[k], std::abs(d[0] * axis[k][0] + d[1] * axis[k][1] + d[2] * axis[k][2]) + err);
    };
    for (int k = 0; k < 3; ++k) half[k] = 0.0;
    if (nd.leaf()) {
      for (std::uint32_t s = nd.a; s < nd.b; ++s) reach_of(t.xs()[s], t.ys()[s], t.zs()[s], half);
    } else {
      for (const std::uint32_t child : {static_cast<std::uint32_t>(i + 1), nd.a}) {
        const Sums& cz = sums[child];
        if (cz.count == 0.0) continue;
        double by_box[3] = {0.0, 0.0, 0.0};  // from the child's axis-aligned box's corners (exact)
        for (int k = 0; k < 8; ++k)
          reach_of((k & 1) ? cz.hi[0] : cz.lo[0], (k & 2) ? cz.hi[1] : cz.lo[1], (k & 4) ? cz.hi[2] : cz.lo[2], by_box);
        const NodeFrame& cf = frame[child];
        if (!(cf.half[0] >= 0.0f)) {  // no oriented box (a single point)
          for (int k = 0; k < 3; ++k) half[k] = std::max(half[k], by_box[k]);
          continue;
        }
        const double cc[3] = {cf.c[0], cf.c[1], cf.c[2]};
        const double ca[3][3] = {{cf.axis[0][0], cf.axis[0][1], cf.axis[0][2]},
                                 {cf.axis[1][0], cf.axis[1][1], cf.axis[1][2]},
                                 {cf.axis[2][0], cf.axis[2][1], cf.axis[2][2]}};
        const double ch[3] = {cf.half[0], cf.half[1], cf.half[2]};
        Eigen::Vector3d oriented[8];
        corners(cc, ca, ch, oriented);
        double by_frame[3] = {0.0, 0.0, 0.0};  // from its oriented box's corners
        for (const Eigen::Vector3d& q : oriented) reach_of(q[0], q[1], q[2], by_frame);
        // The float axes' error, and the corners' own rounding (a few ulps of |c| + the half extents).
        const double margin = 1e-6 * (ch[0] + ch[1] + ch[2]) +
                              2e-15 * (std::abs(cc[0]) + std::abs(cc[1]) + std::abs(cc[2]) + 3.0 * (ch[0] + ch[1] + ch[2]));
        for (int k = 0; k < 3; ++k) half[k] = std::max(half[k], std::min(by_box[k], by_frame[k] + margin));
      }
    }
    double thinnest = HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
      float hf = static_cast<float>(half[k]);
      if (static_cast<double>(hf) < half[k]) hf = std::nextafter(hf, std::numeric_limits<float>::infinity());
      g.half[k] = hf;
      thinnest = std::min(thinnest, half[k]);
    }
    if (thinnest < kThinner * 0.5 * (z.hi - z.lo).minCoeff()) {
      kept.push_back(static_cast<std::uint32_t>(i));
      if (!t.nodes[i].leaf()) t.nodes[i].b |= kFramed;
    }
  }
  // In pre-order, as the nodes; none kept: no index either (frame_bound() then stops at the empty list).
  t.frames.clear();
  if (kept.empty()) std::vector<std::uint32_t>().swap(t.frame_of);
  t.frames.reserve(kept.size());
  for (std::size_t k = kept.size(); k-- > 0;) {
    t.frame_of[kept[k]] = static_cast<std::uint32_t>(t.frames.size());
    t.frames.push_back(frame[kept[k]]);
  }
}

}  // namespace surfeledit::kd
