// Keeping particles on the original surface (thesis §12.3.7): while iterating, onto the tangent plane of the
// nearest original sample; at the end, a moving-least-squares projection onto the surface the original
// samples define (a weighted plane fit iterated to a fixed point; see docs/particles.md for why not PCL's).
#pragma once

#include <memory>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

class KdTree;

class SurfaceProjector {
 public:
  // The original surface: `positions` and unit `normals`, #S by 3 each, #S >= 1.
  SurfaceProjector(const Points& positions, const Points& normals);
  ~SurfaceProjector();
  SurfaceProjector(SurfaceProjector&&) noexcept;
  SurfaceProjector& operator=(SurfaceProjector&&) noexcept;

  // x moved onto the tangent plane of the nearest original sample.
  Vec3 onto_tangent_plane(const Vec3& x) const;
  // x moved onto the MLS surface: Gaussian weights exp(-dist2 / h^2) over samples within 3 h, plane through
  // their weighted centroid normal to their weighted mean normal, repeated until it moves less than 1e-9 h.
  // `normal` (optional) gets the plane normal. x is returned unchanged when no sample is within 3 h.
  Vec3 onto_mls(const Vec3& x, double h, Vec3* normal = nullptr) const;

 private:
  Points positions_, normals_;
  std::unique_ptr<KdTree> tree_;
};

}  // namespace surfeledit
