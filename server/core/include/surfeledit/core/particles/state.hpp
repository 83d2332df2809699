// State of an oriented particle system (thesis §12.2.1, docs/algorithms.md §8): position, unit quaternion,
// velocity and angular velocity per particle; mass 1 and identity inertia. The normal of a particle is the
// third column of its rotation (R = [u v n]).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

struct ParticleState {
  Points x;                              // #P by 3 positions (model units)
  std::vector<Eigen::Quaterniond> q;     // #P unit orientations
  Points v;                              // #P by 3 velocities (Leapfrog: at the last half step)
  Points w;                              // #P by 3 angular velocities (rad per unit time)
  Points v_prev;                         // #P by 3 Leapfrog: the half-step velocity one step earlier
  Points w_prev;                         // #P by 3 (Eq. 12.27 extrapolates the damping velocity from both)
  int steps = 0;                         // integration steps taken (Leapfrog starts with a half kick)
  std::vector<std::int64_t> origin;      // #P caller's tags: from_surfels gives 0..#P-1; a copy of a particle
                                         // with tag t gets -1 - t (t >= 0) or t (t < 0): -1 - origin row

  Index size() const { return static_cast<Index>(x.rows()); }
  Vec3 normal(Index i) const { return q[i] * Vec3::UnitZ(); }
  Vec3 tangent(Index i) const { return q[i] * Vec3::UnitX(); }
  Points normals() const;  // #P by 3

  // Particles at `positions` (#P by 3) with normals `normals` (#P by 3, need not be unit; non-zero), at rest.
  static ParticleState from_surfels(const Points& positions, const Points& normals);
  // Appends a copy of particle `i` moved to `at`, at rest.
  void append_copy(Index i, const Vec3& at);
  // Keeps the particles whose flag is set, in order.
  void keep(const std::vector<bool>& flags);
};

}  // namespace surfeledit
