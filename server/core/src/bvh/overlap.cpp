// The full 15-axis separating-axis test for an OBB against an AABB (thesis §8.2.2.2, Eq. 8.8),
// and the SatMode names.
#include "surfeledit/core/bvh/overlap.hpp"

#include <Eigen/Geometry>

namespace surfeledit::bvh {

bool overlap_sat_full(const Obb& o, const Aabb& box) {
  if (!overlap_sat_lite(o, box)) return false;  // the 6 face axes
  const Vec3 a = box.half_extents();
  const Vec3 t = o.center - box.center();
  // The 9 edge-edge axes L = e_d x B_j. For L the intervals are disjoint iff
  //   |T . L| > sum_k a_k |e_k . L| + sum_k b_k |B_k . L|   (Eq. 8.8).
  // Near-parallel pairs give a near-zero L that cannot separate better than the face axes: skipped.
  for (int d = 0; d < 3; ++d) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 l = Vec3::Unit(d).cross(o.axes.row(j).transpose());
      const double len2 = l.squaredNorm();
      if (len2 < 1e-18) continue;
      const double ra = a.dot(l.cwiseAbs());
      const double rb = o.ext.dot((o.axes * l).cwiseAbs());
      // Relative slack so that touching boxes count as overlapping despite rounding.
      if (std::abs(t.dot(l)) > (ra + rb) * (1.0 + 1e-12)) return false;
    }
  }
  return true;
}

}  // namespace surfeledit::bvh
