// Compact and cut-Gaussian weighting functions with their derivatives (thesis §12.2.5).
#include "surfeledit/core/particles/weighting.hpp"

#include <cmath>

namespace surfeledit {

WeightSample weight(const WeightParams& params, double r) {
  WeightSample w;
  const double d = params.radius;
  if (r >= d) return w;
  const double d2 = d * d;
  if (params.kind == WeightKind::Compact) {
    const double t2 = r * r / d2;
    const double u = t2 - 1.0;
    w.phi = u * u;
    w.dphi_r = 4.0 * u / d2;
    w.dphi = w.dphi_r * r;
    w.ddphi = 4.0 * (3.0 * t2 - 1.0) / d2;
  } else {
    const double sigma2 = -d2 / (2.0 * std::log(params.eps));  // phi(d) = eps
    w.phi = std::exp(-r * r / (2.0 * sigma2));
    w.dphi_r = -w.phi / sigma2;
    w.dphi = w.dphi_r * r;
    w.ddphi = (r * r / (sigma2 * sigma2) - 1.0 / sigma2) * w.phi;
  }
  return w;
}

}  // namespace surfeledit
