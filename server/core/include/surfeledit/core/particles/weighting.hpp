// Distance weighting of the particle interactions (thesis §12.2.5, docs/algorithms.md §8): every pair
// potential is multiplied by phi(|r|), which falls from 1 at r = 0 to 0 at the neighbourhood radius d.
#pragma once

#include <cstdint>

namespace surfeledit {

enum class WeightKind : std::uint8_t {
  Compact = 0,      // phi(r) = (r^2/d^2 - 1)^2 for r < d, 0 beyond (Eq. 12.20; the thesis prefers it)
  CutGaussian = 1,  // phi(r) = exp(-r^2 / (2 sigma_r^2)), sigma_r^2 = -d^2 / (2 ln eps), 0 for r >= d (Eq. 12.18-12.19)
};


struct WeightParams {
  WeightKind kind = WeightKind::Compact;  // which weighting function
  double radius = 1.0;                    // d: neighbourhood radius (model units), > 0
  double eps = 0.01;                      // CutGaussian only: phi(d) = eps, in (0, 1)
};

// phi and its first two derivatives with respect to the distance r (model units^-1, ^-2).
struct WeightSample {
  double phi = 0.0;
  double dphi = 0.0;   // d phi / d r
  double ddphi = 0.0;  // d^2 phi / d r^2
  double dphi_r = 0.0; // phi' / r (finite at r = 0), so that phi' r_hat = dphi_r * r without a division
};

// phi at distance r >= 0 (zero for r >= radius).
WeightSample weight(const WeightParams& params, double r);

}  // namespace surfeledit
