// Distance weighting of the particle interactions (thesis §12.2.5, docs/algorithms.md §8): every pair
// potential is multiplied by phi(|r|), which falls from 1 at r = 0 to 0 at the neighbourhood radius d.
#pragma once

#include <cmath>
#include <cstdint>

#include "surfeledit/core/enum_names.hpp"

namespace surfeledit {

enum class WeightKind : std::uint8_t {
  Compact = 0,      // phi(r) = (r^2/d^2 - 1)^2 for r < d, 0 beyond (Eq. 12.20; the thesis prefers it)
  CutGaussian = 1,  // phi(r) = exp(-r^2 / (2 sigma_r^2)), sigma_r^2 = -d^2 / (2 ln eps), 0 for r >= d (Eq. 12.18-12.19)
};
constexpr EnumNames<WeightKind, 2> names_of(WeightKind) {
  return {{{WeightKind::Compact, "compact"}, {WeightKind::CutGaussian, "gaussian"}}};
}


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

// The compact weight at r < d (d2 = d^2), without the range test: the branch-free core of weight(), also
// evaluated by the vectorised pair kernel of compute_forces.
inline WeightSample compact_weight_inside(double r, double d2) {
  WeightSample w;
  const double t2 = r * r / d2;
  const double u = t2 - 1.0;
  w.phi = u * u;
  w.dphi_r = 4.0 * u / d2;
  w.dphi = w.dphi_r * r;
  w.ddphi = 4.0 * (3.0 * t2 - 1.0) / d2;
  return w;
}

// phi at distance r >= 0 (zero for r >= radius). Inline: it is evaluated once per neighbour pair.
inline WeightSample weight(const WeightParams& params, double r) {
  const double d = params.radius;
  if (r >= d) return WeightSample{};
  const double d2 = d * d;
  if (params.kind == WeightKind::Compact) return compact_weight_inside(r, d2);
  WeightSample w;
  const double sigma2 = -d2 / (2.0 * std::log(params.eps));  // phi(d) = eps
  w.phi = std::exp(-r * r / (2.0 * sigma2));
  w.dphi_r = -w.phi / sigma2;
  w.dphi = w.dphi_r * r;
  w.ddphi = (r * r / (sigma2 * sigma2) - 1.0 / sigma2) * w.phi;
  return w;
}

}  // namespace surfeledit
