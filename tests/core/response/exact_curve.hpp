// The exact intersection curve of a ResponseScene, sampled densely: fine samples of each deformed
// solid near the zero solids, projected alternately onto both exact surfaces (sdf gradients by
// central differences) until they lie on both.
#pragma once

#include <cmath>
#include <vector>

#include "response_scenes.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit::testing {

template <typename F>
Vec3 numeric_gradient(const F& f, const Vec3& p, double h) {
  Vec3 g;
  for (int d = 0; d < 3; ++d) {
    Vec3 a = p, b = p;
    a[d] += h;
    b[d] -= h;
    g[d] = (f(a) - f(b)) / (2.0 * h);
  }
  return g;
}

// The largest distance from a row of `from` (#F by 3) to its nearest row of `to` (#T by 3).
inline double max_nearest_distance(const Points& from, const Points& to) {
  const KdTree tree(to);
  double worst2 = 0.0;
  for (Eigen::Index i = 0; i < from.rows(); ++i) {
    double dist2 = 0.0;
    tree.nearest(from.row(i).transpose(), &dist2);
    worst2 = std::max(worst2, dist2);
  }
  return std::sqrt(worst2);
}

struct ExactCurve {
  Points points;  // #C by 3 on both surfaces (to 1e-6 spacing), ~spacing/10 apart
};

inline ExactCurve exact_curve(const ResponseScene& sc) {
  const double s = sc.spacing, h = 1e-2 * s;
  std::vector<Vec3> pts;
  for (const auto& solid : sc.deformed) {
    SampleParams sp;
    sp.spacing = s / 10.0;
    sp.jitter = 0.0;
    const SampledSurfels fine = solid->sample(sp);
    auto f = [&](const Vec3& q) { return solid->sdf(q); };
    auto g = [&](const Vec3& q) { return sc.sdf_zero(q); };
    for (Eigen::Index i = 0; i < fine.positions.rows(); ++i) {
      Vec3 p = fine.positions.row(i).transpose();
      if (std::abs(g(p)) > 0.5 * s) continue;
      for (int it = 0; it < 40; ++it) {
        Vec3 gf = numeric_gradient(f, p, h);
        p -= f(p) * gf / gf.squaredNorm();
        Vec3 gg = numeric_gradient(g, p, h);
        p -= g(p) * gg / gg.squaredNorm();
      }
      if (std::abs(f(p)) < 1e-6 * s && std::abs(g(p)) < 1e-6 * s) pts.push_back(p);
    }
  }
  ExactCurve c;
  c.points.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t k = 0; k < pts.size(); ++k) c.points.row(static_cast<Eigen::Index>(k)) = pts[k].transpose();
  return c;
}

}  // namespace surfeledit::testing
