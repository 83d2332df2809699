// Merge scenes from the analytic solids (exact signed distances) for the response tests and bench:
// zero solids stay, deformable solids are sampled at their start pose and moved rigidly into the zero
// ones; the colliding set comes from the Robust detector. A Frame scales and translates a whole scene
// (numerical extremes).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit::testing {

// world = scale * local + offset.
struct Frame {
  double scale = 1.0;
  Vec3 offset = Vec3::Zero();
  Vec3 at(const Vec3& p) const { return scale * p + offset; }
  Pose pose(const Vec3& centre, const Mat3& rotation = Mat3::Identity()) const {
    Pose p;
    p.rotation = rotation;
    p.translation = at(centre);
    return p;
  }
};

// The numerical extremes: translated by 1e6, scaled by 1e-4 and 1e4, and both.
inline std::vector<Frame> extreme_frames() {
  return {{1.0, Vec3(1e6, -1e6, 1e6)}, {1e-4, Vec3::Zero()}, {1e4, Vec3::Zero()}, {1e-4, Vec3(1e6, 0, 0)}};
}

// A rigid motion about a pivot: p -> R (p - pivot) + pivot + t (world units).
struct Motion {
  Mat3 rotation = Mat3::Identity();
  Vec3 pivot = Vec3::Zero();
  Vec3 translation = Vec3::Zero();
  Vec3 apply(const Vec3& p) const { return rotation * (p - pivot) + pivot + translation; }
};

struct ResponseScene {
  std::vector<std::unique_ptr<Solid>> zero;      // the rigid solids
  std::vector<std::unique_ptr<Solid>> deformed;  // the deformable solids, at their pose after the motion
  double spacing = 0.0;                          // sample spacing (= surfel radius), world units
  SurfelModel model;                             // deformed model: zero surfels, then deformable ones
  std::vector<Region> regions;                   // #P
  Points original_positions, original_normals;   // #D by 3: deformable surfels before the motion
  IdList colliding;                              // Robust detector's colliding ids

  static double min_sdf(const std::vector<std::unique_ptr<Solid>>& solids, const Vec3& p) {
    double d = INFINITY;
    for (const auto& s : solids) d = std::min(d, s->sdf(p));
    return d;
  }
  double sdf_zero(const Vec3& p) const { return min_sdf(zero, p); }
  double sdf_deformed(const Vec3& p) const { return min_sdf(deformed, p); }
  // Signed distance to the solids of the other side than row r's.
  double sdf_other(Index r) const {
    const Vec3 p = model.positions().row(r).transpose();
    return regions[r] == Region::Zero ? sdf_deformed(p) : sdf_zero(p);
  }
  double sdf_own(const Vec3& p, Region region) const {
    return region == Region::Zero ? sdf_zero(p) : sdf_deformed(p);
  }
};

inline void append(SampledSurfels& all, const SampledSurfels& s) {
  const Eigen::Index n = all.positions.rows(), m = s.positions.rows();
  all.positions.conservativeResize(n + m, 3);
  all.normals.conservativeResize(n + m, 3);
  all.radii.conservativeResize(n + m);
  all.positions.bottomRows(m) = s.positions;
  all.normals.bottomRows(m) = s.normals;
  all.radii.tail(m) = s.radii;
}

// A scene from samples: the zero surfels stay, the deformable ones move by `motion`; the Robust detector
// runs over the move (one step). The solids are left to the caller.
inline ResponseScene build_from_samples(const SampledSurfels& zero, const SampledSurfels& deformable,
                                        const Motion& motion, double spacing) {
  ResponseScene sc;
  sc.spacing = spacing;
  SampledSurfels all = zero;
  const Index nz = static_cast<Index>(all.positions.rows());
  sc.original_positions = deformable.positions;
  sc.original_normals = deformable.normals;
  append(all, deformable);
  const Index n = static_cast<Index>(all.positions.rows());
  sc.regions.assign(static_cast<std::size_t>(n), Region::Zero);
  for (Index r = nz; r < n; ++r) sc.regions[static_cast<std::size_t>(r)] = Region::One;

  const Points before = all.positions;
  CollisionParams cp;
  cp.threads = 1;
  auto detector = CollisionDetector::create(cp);
  detector->reset({all.positions, all.normals, all.radii, sc.regions});
  for (Index r = nz; r < n; ++r) {
    all.positions.row(r) = motion.apply(all.positions.row(r).transpose()).transpose();
    all.normals.row(r) = (motion.rotation * all.normals.row(r).transpose()).transpose();
  }
  const CollisionResult hit = detector->detect({all.positions, all.normals, all.radii, sc.regions}, before);
  SurfelArrays arrays;
  arrays.positions = all.positions;
  arrays.normals = all.normals;
  arrays.radii = all.radii;
  sc.model = SurfelModel::from_arrays(std::move(arrays));
  for (Index r : hit.colliding) sc.colliding.push_back(sc.model.id_of(r));
  return sc;
}

// Samples every solid at `spacing` and moves the deformable ones (samples and solids) by `motion`.
inline ResponseScene build_scene(std::vector<std::unique_ptr<Solid>> zero,
                                 std::vector<std::unique_ptr<Solid>> deformable, const Motion& motion,
                                 double spacing) {
  SampleParams sp;
  sp.spacing = spacing;
  SampledSurfels z, d;
  for (const auto& s : zero) {
    append(z, s->sample(sp));
    ++sp.seed;
  }
  for (const auto& s : deformable) {
    append(d, s->sample(sp));
    ++sp.seed;
  }
  ResponseScene sc = build_from_samples(z, d, motion, spacing);
  for (auto& s : deformable) {
    s->pose.translation = motion.apply(s->pose.translation);
    s->pose.rotation = motion.rotation * s->pose.rotation;
  }
  sc.zero = std::move(zero);
  sc.deformed = std::move(deformable);
  return sc;
}

inline Mat3 generic_rotation(double angle = 0.7) {
  return Eigen::AngleAxisd(angle, Vec3(1, 2, 3).normalized()).toRotationMatrix();
}

// A sphere pushed down into a box.
inline ResponseScene sphere_into_box(const Frame& f = {}, double spacing = 0.05) {
  std::vector<std::unique_ptr<Solid>> zero, def;
  zero.push_back(make_box(f.scale * Vec3(1.0, 1.0, 0.25), f.pose(Vec3::Zero())));
  def.push_back(make_sphere(f.scale * 0.5, f.pose(Vec3(0.1, 0.05, 0.85), generic_rotation())));
  Motion m;
  m.translation = f.scale * Vec3(0, 0, -0.3);
  return build_scene(std::move(zero), std::move(def), m, f.scale * spacing);
}

// A capsule arm (pivot at one end) rotated about z into a sphere.
inline ResponseScene arm_into_sphere(const Frame& f = {}, double spacing = 0.025) {
  std::vector<std::unique_ptr<Solid>> zero, def;
  const Mat3 along_x = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).toRotationMatrix();
  def.push_back(make_capsule(f.scale * 0.15, f.scale * 0.5, f.pose(Vec3(0.6, 0, 0), along_x)));
  zero.push_back(make_sphere(f.scale * 0.3, f.pose(Vec3(0.1 + std::cos(0.8), std::sin(0.8), 0.02),
                                                   generic_rotation())));
  Motion m;
  m.rotation = Eigen::AngleAxisd(0.6, Vec3::UnitZ()).toRotationMatrix();
  m.pivot = f.at(Vec3(0.1, 0, 0));
  return build_scene(std::move(zero), std::move(def), m, f.scale * spacing);
}

// A ball pushed sideways into the inner wall of a cup (a concave rigid part).
inline ResponseScene ball_into_cup(const Frame& f = {}, double spacing = 0.025) {
  std::vector<std::unique_ptr<Solid>> zero, def;
  zero.push_back(make_cup(f.scale * 0.5, f.scale * 1.0, f.scale * 0.08, f.scale * 0.25, f.scale * 0.05,
                          f.pose(Vec3::Zero())));
  def.push_back(make_sphere(f.scale * 0.15, f.pose(Vec3(0.0, 0.15, 0.55), generic_rotation())));
  Motion m;
  m.translation = f.scale * Vec3(0, 0.18, 0);
  return build_scene(std::move(zero), std::move(def), m, f.scale * spacing);
}

// Two balls pushed down into a box at once: two separate contacts.
inline ResponseScene two_contacts(const Frame& f = {}, double spacing = 0.05) {
  std::vector<std::unique_ptr<Solid>> zero, def;
  zero.push_back(make_box(f.scale * Vec3(1.2, 0.8, 0.25), f.pose(Vec3::Zero())));
  def.push_back(make_sphere(f.scale * 0.35, f.pose(Vec3(-0.6, 0.0, 0.7), generic_rotation())));
  def.push_back(make_sphere(f.scale * 0.3, f.pose(Vec3(0.6, 0.1, 0.65), generic_rotation(1.3))));
  Motion m;
  m.translation = f.scale * Vec3(0, 0, -0.25);
  return build_scene(std::move(zero), std::move(def), m, f.scale * spacing);
}

}  // namespace surfeledit::testing
