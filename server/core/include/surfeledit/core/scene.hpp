// Analytic closed solids sampled into surfels, with exact normals and an exact
// signed distance (negative inside). The ground truth of every accuracy test and
// the default demo scene.
#pragma once

#include <memory>
#include <string>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

// Rigid placement of a solid: world = rotation * local + translation.
struct Pose {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
};

// Surfels sampled from a solid or a scene. All arrays have #P rows.
struct SampledSurfels {
  Points positions;            // #P by 3
  Points normals;              // #P by 3, unit, outward, exact
  Values radii;                // #P, disc radii (= spacing)
  std::vector<int> part;       // #P, index of the solid in its scene (0 for a lone solid)
};

struct SampleParams {
  double spacing = 0.05;  // target distance between neighbouring samples, model units
  std::uint64_t seed = 1; // seeds phase offsets and jitter; same seed -> same samples
  double jitter = 0.25;   // random offset in parameter space, as a fraction of the spacing (0 = regular)
};

class Solid {
 public:
  virtual ~Solid() = default;
  virtual std::string kind() const = 0;
  // Signed distance of a world point: < 0 inside, > 0 outside. The sign is exact
  // everywhere; the magnitude is exact for primitives and, for unions (the cup),
  // exact outside and a lower bound of the depth inside.
  virtual double sdf(const Vec3& p) const = 0;
  // Surface samples with exact outward normals.
  virtual SampledSurfels sample(const SampleParams& params) const = 0;
  // Area of the surface (for sample counts and tests).
  virtual double area() const = 0;

  Pose pose;
};

// Factories. Dimensions in model units, in the solid's local frame (centred at the origin,
// axis of symmetry along local z), then placed by `pose`. Each throws InvalidArgument
// (naming the field) on a non-positive or non-finite dimension.
std::unique_ptr<Solid> make_sphere(double radius, Pose pose = {});
std::unique_ptr<Solid> make_box(const Vec3& half_extents, Pose pose = {});
std::unique_ptr<Solid> make_cylinder(double radius, double half_height, Pose pose = {});
std::unique_ptr<Solid> make_torus(double major_radius, double minor_radius, Pose pose = {});
// Segment from (0,0,-half_length) to (0,0,+half_length), swept by a ball of `radius`.
std::unique_ptr<Solid> make_capsule(double radius, double half_length, Pose pose = {});
// Open-top cup: outer radius, height (base at local z = 0), wall thickness, and a handle
// (half torus in the x-z plane on the +x side). The solid is the cup's material.
std::unique_ptr<Solid> make_cup(double radius = 0.5, double height = 1.0, double wall = 0.08,
                                double handle_major = 0.25, double handle_minor = 0.05, Pose pose = {});

// A union of solids, sampled part by part (samples of one part lying strictly inside
// another are dropped so the surface stays that of the union).
class Scene {
 public:
  void add(std::unique_ptr<Solid> solid);
  std::size_t parts() const { return solids_.size(); }
  const Solid& part(std::size_t i) const { return *solids_.at(i); }
  // min over parts: exact sign of the union.
  double sdf(const Vec3& p) const;
  // #Q signed distances to part `i` (or the union when i < 0).
  Values sdf(const Points& queries, int i = -1) const;
  SampledSurfels sample(const SampleParams& params) const;

 private:
  std::vector<std::unique_ptr<Solid>> solids_;
};

// The self-contained default scene of the demo: a rigid box slab with a sphere
// above it (the deformable part), well separated.
Scene make_default_scene();

}  // namespace surfeledit
