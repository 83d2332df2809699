// The fused pair kernel of compute_forces (forces.cpp, its only includer: compiled without FMA contraction,
// which the bit-identical results of every variant and thread count rely on). A block holds up to kLanes
// pairs (i, j) of one row as structure of arrays; the kernels fill its result arrays lane by lane.
#pragma once

#include <cmath>

#include "surfeledit/core/particles/params.hpp"
#include "surfeledit/core/particles/repulsion.hpp"

namespace surfeledit::fused_pairs {

#define SURFELEDIT_INLINE [[gnu::always_inline]] inline

constexpr int kLanes = 64;  // pairs evaluated together: one row's upper neighbours, in blocks
constexpr int kPad = 4;     // lanes evaluated in multiples of this (divides kLanes; the row pass moves
                            // lanes in groups of four)

// Pairs (i, j_l), i < j_l, r_l = x_j - x_i, as structure of arrays so that the pair kernel vectorises.
struct PairBlock {
  int size = 0;
  double rx[kLanes], ry[kLanes], rz[kLanes], njx[kLanes], njy[kLanes], njz[kLanes];  // r and n_j
  double rho[kLanes];                                                                // |r|
  double phi[kLanes], dphi[kLanes], ddphi[kLanes], dphi_r[kLanes];  // weight at |r| (0 at and beyond d)
  double e_rep[kLanes], d1_rep[kLanes], k_rep[kLanes];              // repulsion: Phi, Phi'/rho, stiffness
  // Results: force on i (-f on j: Newton's third law holds exactly for every term), torques on i and on j
  // (not antisymmetric), stiffness bound (the same at both ends), E_ij = 2 a_R Phi_R + a_P (Phi_P(n_i) +
  // Phi_P(n_j)) + 2 a_N Phi_N + 2 a_C Phi_C.
  double fx[kLanes], fy[kLanes], fz[kLanes], tix[kLanes], tiy[kLanes], tiz[kLanes];
  double tjx[kLanes], tjy[kLanes], tjz[kLanes], k[kLanes], e[kLanes];
};

// phi and the repulsion at |r| for every lane; lanes at or beyond the radius get zeros (they add nothing).
SURFELEDIT_INLINE void radial_terms(const ParticleParams& p, PairBlock& b) {
  const int m = b.size;
#pragma omp simd
  for (int l = 0; l < m; ++l) b.rho[l] = std::sqrt(b.rx[l] * b.rx[l] + b.ry[l] * b.ry[l] + b.rz[l] * b.rz[l]);
  const double d = p.weight.radius, d2 = d * d;
  if (p.weight.kind == WeightKind::Compact) {
#pragma omp simd
    for (int l = 0; l < m; ++l) {
      const double in = static_cast<double>(b.rho[l] < d);  // 1 or 0, without a branch
      const WeightSample w = compact_weight_inside(b.rho[l], d2);
      b.phi[l] = in * w.phi;
      b.dphi[l] = in * w.dphi;
      b.ddphi[l] = in * w.ddphi;
      b.dphi_r[l] = in * w.dphi_r;
    }
  } else {
    for (int l = 0; l < m; ++l) {
      const WeightSample w = weight(p.weight, b.rho[l]);
      b.phi[l] = w.phi, b.dphi[l] = w.dphi, b.ddphi[l] = w.ddphi, b.dphi_r[l] = w.dphi_r;
    }
  }
  if (p.repulsion.kind == RepulsionKind::Weight) {
    const double A = p.repulsion.amplitude;
#pragma omp simd
    for (int l = 0; l < m; ++l) {
      const RadialTerm t = weight_repulsion(A, WeightSample{b.phi[l], b.dphi[l], b.ddphi[l], b.dphi_r[l]});
      b.e_rep[l] = t.energy, b.d1_rep[l] = t.d1_r, b.k_rep[l] = t.stiffness;
    }
  } else {
    for (int l = 0; l < m; ++l) {
      const WeightSample w{b.phi[l], b.dphi[l], b.ddphi[l], b.dphi_r[l]};
      // Beyond the radius every term is off, the repulsion too (it interacts only within a neighbourhood).
      const RadialTerm t = (w.phi == 0.0 && w.dphi == 0.0) ? RadialTerm{} : repulsion_radial(p.repulsion, b.rho[l], w);
      b.e_rep[l] = t.energy, b.d1_rep[l] = t.d1_r, b.k_rep[l] = t.stiffness;
    }
  }
}

// The terms of potentials.hpp and repulsion.hpp for lane l, written out with their common factors shared (a
// term whose alpha is 0 adds zeros). `ni` is the normal of particle i; `w`, `e_rep`, `d1_rep`, `k_rep` the
// lane's weight and repulsion.
struct PairCoefficients {
  double aP, aN, aC, aR, keep_dphi;
  double kA, kB, kC;  // the stiffness bounds 2 aP P(1) + aC P(2) as a polynomial in m, see pair_lane
  explicit PairCoefficients(const ParticleParams& p)
      : aP(p.alpha_planarity),
        aN(2.0 * p.alpha_normality),
        aC(2.0 * p.alpha_circularity),
        aR(p.repulsion.kind == RepulsionKind::None ? 0.0 : 2.0 * p.alpha_repulsion),
        keep_dphi(p.drop_dphi ? 0.0 : 1.0),
        kA(2.0 * aP + 4.0 * aC),
        kB(2.0 * aP + 2.0 * aC),
        kC(2.0 * aP + aC) {}
};
// The energy and the radial force share S = aP ((n_i.r)^2 + (n_j.r)^2) + aN |n_i - n_j|^2 + aC c^2:
// E = phi S + aR Phi_R, and the force's r coefficient is (phi' / rho) S + aR Phi_R' / rho.
// projection_stiffness(m, rho, w) = m^2 P2 + m P1 + P0 (P2 = 2 phi + 4 rho |phi'| + rho^2 (|phi''| +
// |phi' / rho|), P1 = 2 rho^2 phi + 4 rho phi + 2 rho^2 |phi'|, P0 = 2 rho^2 phi), so co-planarity (m = 1,
// twice) and co-circularity (m = 2) together are kA P2 + kB P1 + kC P0: the same bound, a third of the work.
[[gnu::always_inline]] inline void pair_lane(const PairCoefficients& a, double nix, double niy, double niz, const WeightSample& w, double rho,
                      double e_rep, double d1_rep, double k_rep, PairBlock& b, int l) {
  const double aP = a.aP, aN = a.aN, aC = a.aC, aR = a.aR;
  const double rx = b.rx[l], ry = b.ry[l], rz = b.rz[l], njx = b.njx[l], njy = b.njy[l], njz = b.njz[l];
  const double phi = w.phi, dr = a.keep_dphi * w.dphi_r, phi2 = 2.0 * phi;
  const double ai = nix * rx + niy * ry + niz * rz, aj = njx * rx + njy * ry + njz * rz;  // Phi_P: n . r
  const double bx = nix - njx, by = niy - njy, bz = niz - njz, bn = bx * bx + by * by + bz * bz;  // Phi_N
  const double c = (nix + njx) * rx + (niy + njy) * ry + (niz + njz) * rz;  // Phi_C: (n_i + n_j) . r
  const double S = aP * (ai * ai + aj * aj) + aN * bn + aC * (c * c);
  b.e[l] = phi * S + aR * e_rep;
  const double rc = dr * S + aR * d1_rep;
  const double cc = aC * c, ci = phi2 * (aP * ai + cc), cj = phi2 * (aP * aj + cc);
  const double tn = aN * phi2;
  const double adphi = std::abs(w.dphi), add = std::abs(w.ddphi) + std::abs(w.dphi_r), rr = rho * rho;
  const double rr_phi2 = rr * phi2;
  const double P2 = phi2 + 4.0 * rho * adphi + rr * add, P1 = rr_phi2 + 2.0 * rho * phi2 + 2.0 * rr * adphi;
  b.k[l] = a.kA * P2 + a.kB * P1 + a.kC * rr_phi2 + aN * (bn * add + phi2 + 2.0 * adphi) + aR * k_rep;
  // f = rc r + ci n_i + cj n_j; torques: -grad over a rotation of i is (dPhi/dn_i) x n_i, for j the same
  // with r -> -r: t_i = ci r x n_i + tn n_i x n_j, t_j = cj r x n_j - tn n_i x n_j.
  b.fx[l] = rc * rx + ci * nix + cj * njx;
  b.fy[l] = rc * ry + ci * niy + cj * njy;
  b.fz[l] = rc * rz + ci * niz + cj * njz;
  const double nnx = tn * (niy * njz - niz * njy), nny = tn * (niz * njx - nix * njz), nnz = tn * (nix * njy - niy * njx);
  b.tix[l] = ci * (ry * niz - rz * niy) + nnx;
  b.tiy[l] = ci * (rz * nix - rx * niz) + nny;
  b.tiz[l] = ci * (rx * niy - ry * nix) + nnz;
  b.tjx[l] = cj * (ry * njz - rz * njy) - nnx;
  b.tjy[l] = cj * (rz * njx - rx * njz) - nny;
  b.tjz[l] = cj * (rx * njy - ry * njx) - nnz;
}

// Every lane after radial_terms.
SURFELEDIT_INLINE void pair_kernel(const ParticleParams& p, const Vec3& ni, PairBlock& b) {
  const PairCoefficients a(p);
  const double nix = ni.x(), niy = ni.y(), niz = ni.z();
  const int m = b.size;
#pragma omp simd
  for (int l = 0; l < m; ++l)
    pair_lane(a, nix, niy, niz, WeightSample{b.phi[l], b.dphi[l], b.ddphi[l], b.dphi_r[l]}, b.rho[l], b.e_rep[l],
              b.d1_rep[l], b.k_rep[l], b, l);
}

// The common case in one pass: compact weight, weight-based repulsion (or none). The same expressions as
// radial_terms followed by pair_kernel (up to the rounding of the weight, see below), without storing the
// radial terms.
SURFELEDIT_INLINE void compact_kernel(const ParticleParams& p, const Vec3& ni, PairBlock& b) {
  const PairCoefficients a(p);
  const double nix = ni.x(), niy = ni.y(), niz = ni.z();
  const double d = p.weight.radius, d2 = d * d, inv_d2 = 1.0 / d2, A = p.repulsion.amplitude;
  const int m = b.size;
#pragma omp simd
  for (int l = 0; l < m; ++l) {
    // compact_weight_inside with 1 / d^2 multiplied instead of divided by, and t^2 from |r|^2 rather than
    // from the square root: the sqrt and three divisions were the kernel's critical path.
    const double r2 = b.rx[l] * b.rx[l] + b.ry[l] * b.ry[l] + b.rz[l] * b.rz[l], rho = std::sqrt(r2);
    const double in = static_cast<double>(r2 < d2);  // 1 or 0, without a branch
    const double t2 = r2 * inv_d2, u = t2 - 1.0, dphi_r = 4.0 * u * inv_d2;
    const WeightSample w{in * (u * u), in * (dphi_r * rho), in * (4.0 * (3.0 * t2 - 1.0) * inv_d2), in * dphi_r};
    const RadialTerm t = weight_repulsion(A, w);
    pair_lane(a, nix, niy, niz, w, rho, t.energy, t.d1_r, t.stiffness, b, l);
  }
}

}  // namespace surfeledit::fused_pairs
