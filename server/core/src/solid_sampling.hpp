// Sampling of revolved profile curves (internal to scene.cpp's analytic solids): samples lie exactly
// on the surface, in rings of equal arc length about one spacing apart (density ~1 / spacing^2), each
// moved by jitter inside its own parameter cell. Lengths in model units, areas in model units^2.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit::solid_sampling {

inline constexpr double kPi = 3.14159265358979323846;

// One local-frame sample: position, unit outward normal, and the surface area it stands for.
struct Sample {
  Vec3 p;
  Vec3 n;
  double area;
};

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : gen_(seed) {}
  double unit() { return static_cast<double>(gen_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double sym() { return 2.0 * unit() - 1.0; }                                 // [-1, 1)

 private:
  std::mt19937_64 gen_;
};

// A point of a profile curve in the (rho, z) half-plane with its unit outward normal (n_rho, n_z).
struct ProfilePoint {
  double rho, z, n_rho, n_z;
};

// Orthonormal frame in which a profile is revolved about local z.
struct Frame {
  Vec3 origin = Vec3::Zero();
  Mat3 axes = Mat3::Identity();  // columns: local x, y, z in the solid's frame
};

// Samples the surface swept by profile(sigma), sigma in [0, length] (arc length, model units),
// revolved over phi in [phi0, phi1] about the frame's z axis.
void sample_revolved(const std::function<ProfilePoint(double)>& profile, double length, double phi0,
                     double phi1, const Frame& frame, double spacing, double jitter, Rng& rng,
                     std::vector<Sample>& out);

// Straight profile segment from (r0, z0) to (r1, z1) with outward normal (nr, nz).
void sample_segment(double r0, double z0, double r1, double z1, double nr, double nz, const Frame& frame,
                    double spacing, double jitter, Rng& rng, std::vector<Sample>& out);

// Circular profile arc: centre (rc, zc), radius r, polar angle theta in [t0, t1] measured from +z
// (point = centre + r (sin theta, cos theta)), outward normal (sin theta, cos theta).
void sample_arc(double rc, double zc, double r, double t0, double t1, double phi0, double phi1,
                const Frame& frame, double spacing, double jitter, Rng& rng, std::vector<Sample>& out);

}  // namespace surfeledit::solid_sampling
