// Repulsion between two particles (thesis §12.2.4, docs/algorithms.md §8): a radial potential Phi_R(|r|) of
// r = x_j - x_i whose force on i is -grad_{x_i} Phi_R (the extracted thesis formulas for the Gaussian and the
// weight-based force are not the gradients of their potentials; we use the gradients).
#pragma once

#include <cstdint>

#include "surfeledit/core/particles/potentials.hpp"

namespace surfeledit {

enum class RepulsionKind : std::uint8_t {
  None = 0,
  Spring = 1,    // Phi = k (|r| - r0)^2: repels closer than r0, attracts beyond (Eq. 12.12-12.13)
  Gaussian = 2,  // Phi = A exp(-|r|^2 / (2 sigma^2)) (Eq. 12.14-12.15)
  Weight = 3,    // Phi = A phi(|r|)^2 (Eq. 12.16-12.17; the thesis found it best)
};


struct RepulsionParams {
  RepulsionKind kind = RepulsionKind::Weight;  // which repulsion potential
  double amplitude = 1.0;                      // A (Gaussian, Weight) or k (Spring), >= 0
  double r0 = 1.0;                             // Spring: equilibrium distance (model units); above every
                                               // neighbour distance it only repels
  double sigma = 0.3;                          // Gaussian: standard deviation (model units), > 0; Witkin and
                                               // Heckbert suggest 0.3 sqrt(area / count)
};

// Phi_R for the pair and its force on i (torque zero). `w` is the weight at |r| (Weight kind only).
PairTerm repulsion(const RepulsionParams& params, const Vec3& r, const WeightSample& w);

}  // namespace surfeledit
