// Sampling of revolved profile curves: see solid_sampling.hpp.
#include "solid_sampling.hpp"

#include <algorithm>
#include <cmath>

namespace surfeledit::solid_sampling {

// Samples the surface swept by profile(sigma), sigma in [0, length] (arc length, model units),
// revolved over phi in [phi0, phi1] about the frame's z axis.
void sample_revolved(const std::function<ProfilePoint(double)>& profile, double length, double phi0,
                     double phi1, const Frame& frame, double spacing, double jitter, Rng& rng,
                     std::vector<Sample>& out) {
  const bool full_turn = (phi1 - phi0) >= 2.0 * kPi - 1e-12;
  const int rings = std::max(1, static_cast<int>(std::lround(length / spacing)));
  const double d_sigma = length / rings;
  for (int k = 0; k < rings; ++k) {
    const ProfilePoint mid = profile((k + 0.5) * d_sigma);
    const double arc = (phi1 - phi0) * mid.rho;
    const int count = std::max(1, static_cast<int>(std::lround(arc / spacing)));
    const double d_phi = (phi1 - phi0) / count;
    const double phase = full_turn ? rng.unit() * d_phi : 0.0;
    for (int m = 0; m < count; ++m) {
      const double sigma = (k + 0.5 + jitter * rng.sym()) * d_sigma;
      const double phi = phi0 + phase + (m + 0.5 + jitter * rng.sym()) * d_phi;
      const ProfilePoint pp = profile(sigma);
      const double c = std::cos(phi), s = std::sin(phi);
      const Vec3 p_local(pp.rho * c, pp.rho * s, pp.z);
      const Vec3 n_local(pp.n_rho * c, pp.n_rho * s, pp.n_z);
      out.push_back({frame.origin + frame.axes * p_local, frame.axes * n_local, d_sigma * d_phi * mid.rho});
    }
  }
}

// Straight profile segment from (r0, z0) to (r1, z1) with outward normal (nr, nz).
void sample_segment(double r0, double z0, double r1, double z1, double nr, double nz, const Frame& frame,
                    double spacing, double jitter, Rng& rng, std::vector<Sample>& out) {
  const double len = std::hypot(r1 - r0, z1 - z0);
  auto profile = [=](double s) {
    const double t = s / len;
    return ProfilePoint{r0 + t * (r1 - r0), z0 + t * (z1 - z0), nr, nz};
  };
  sample_revolved(profile, len, 0.0, 2.0 * kPi, frame, spacing, jitter, rng, out);
}

// Circular profile arc: centre (rc, zc), radius r, polar angle theta in [t0, t1] measured from +z
// (point = centre + r (sin theta, cos theta)), outward normal (sin theta, cos theta).
void sample_arc(double rc, double zc, double r, double t0, double t1, double phi0, double phi1,
                const Frame& frame, double spacing, double jitter, Rng& rng, std::vector<Sample>& out) {
  auto profile = [=](double s) {
    const double th = t0 + s / r;
    const double st = std::sin(th), ct = std::cos(th);
    return ProfilePoint{rc + r * st, zc + r * ct, st, ct};
  };
  sample_revolved(profile, r * (t1 - t0), phi0, phi1, frame, spacing, jitter, rng, out);
}

}  // namespace surfeledit::solid_sampling
