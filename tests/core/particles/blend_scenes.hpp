// Scenes for the blend, boolean and hole-filling tests, with exact signed distances: a capsule pushed into a
// sphere in a session (merged, then blended), and sampled analytic solids.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit::test {

inline SurfelArrays arrays_of(const SampledSurfels& s) {
  SurfelArrays a;
  a.positions = s.positions;
  a.normals = s.normals;
  a.radii = s.radii;
  return a;
}

inline SampledSurfels sample_solid(const Solid& solid, double spacing, std::uint64_t seed = 1) {
  SampleParams sp;
  sp.spacing = spacing;
  sp.seed = seed;
  return solid.sample(sp);
}

// A sphere (zero region, radius 0.3 at the origin) and a capsule along x (one region, radius 0.12, half
// length 0.3, centre (0.75, 0, 0)) translated by (-0.35, 0, 0) in 7 steps: it pierces the sphere, the
// session's response merges them (with the crease). sdf_union is the exact union after the step.
struct CapsuleIntoSphere {
  static constexpr int kSteps = 7;
  double spacing;
  std::unique_ptr<Solid> sphere, capsule;  // capsule at its final pose
  EditSession session;
  MergeOutcome merged;

  explicit CapsuleIntoSphere(double spacing_ = 0.02, int threads = 0)
      : spacing(spacing_), session("blend", SessionParams{threads}) {
    sphere = make_sphere(0.3);
    Pose start;
    start.rotation = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).toRotationMatrix();
    start.translation = Vec3(0.75, 0, 0);
    auto capsule_start = make_capsule(0.12, 0.3, start);
    const SampledSurfels a = sample_solid(*sphere, spacing, 1), b = sample_solid(*capsule_start, spacing, 2);
    SurfelArrays all;
    all.positions.resize(a.positions.rows() + b.positions.rows(), 3);
    all.positions << a.positions, b.positions;
    all.normals.resize(all.positions.rows(), 3);
    all.normals << a.normals, b.normals;
    all.radii.resize(all.positions.rows());
    all.radii << a.radii, b.radii;
    session.load(SurfelModel::from_arrays(all));
    IdList zero, one;
    for (Index r = 0; r < all.positions.rows(); ++r) (r < a.positions.rows() ? zero : one).push_back(r);
    session.set_regions({zero, {}}, {one, {}});
    DeformParams step;
    step.translation = Vec3(-0.35 / kSteps, 0, 0);
    for (int k = 0; k < kSteps; ++k) session.deform(step);
    merged = session.merge(true);
    Pose end = start;
    end.translation = Vec3(0.40, 0, 0);
    capsule = make_capsule(0.12, 0.3, end);
  }
  double sdf_union(const Vec3& p) const { return std::min(sphere->sdf(p), capsule->sdf(p)); }
  // Distance of p to the intersection circle of the two surfaces (x = 0.2742, radius 0.12 about the x axis).
  static double to_crease(const Vec3& p) {
    const double cx = std::sqrt(0.09 - 0.0144);
    return std::hypot(p.x() - cx, std::hypot(p.y(), p.z()) - 0.12);
  }
};

}  // namespace surfeledit::test
