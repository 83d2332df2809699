// Keeping particles on the original surface (thesis §12.3.7): while iterating, onto the tangent plane of the
// nearest original sample; at the end, a moving-least-squares projection onto the surface the original
// samples define (a weighted plane iterated to a fixed point, then a weighted quadratic height over it; see
// docs/particles.md for why not PCL's).
#pragma once

#include <cstdint>
#include <memory>

#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

// What a blend or a hole filling does with its particles at the end (thesis §12.3.7).
enum class ProjectionKind : std::uint8_t {
  Tangent = 0,  // nothing more: they stay where the iterations left them (on the nearest original tangent
                // plane or the constraint surface while iterating, where the run keeps them there)
  Mls = 1,      // then onto the MLS surface of the particles and the surfels around them (onto_mls)
};
constexpr EnumNames<ProjectionKind, 2> names_of(ProjectionKind) {
  return {{{ProjectionKind::Tangent, "tangent"}, {ProjectionKind::Mls, "mls"}}};
}

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
  // their weighted centroid normal to their weighted mean normal, repeated until it moves less than 1e-9 h;
  // then a weighted least-squares quadratic height field over that plane (weights about the foot point),
  // evaluated at the foot point (removes the plane's bias of ~h^2 / (2 R) on a surface of curvature radius
  // R). The plane's answer is kept when fewer than 6 samples are near or the quadratic fit is singular.
  // `normal` (optional) gets the surface normal there, on the side of the samples' normals. x is returned
  // unchanged when no sample is within 3 h.
  Vec3 onto_mls(const Vec3& x, double h, Vec3* normal = nullptr) const;

 private:
  Points positions_, normals_;
  std::unique_ptr<KdTree> tree_;
};

// Every row of `x` (#P by 3) moved onto the MLS surface of `surface` (kernel width h); its row of `normals`
// (#P by 3 unit) becomes the surface normal there. Rows are independent, so the result does not depend on
// `threads` (0 = all).
void project_rows_mls(const SurfaceProjector& surface, double h, Points& x, Points& normals, int threads = 1);

}  // namespace surfeledit
