// Sum of the pair potentials, one fused kernel per unordered neighbour pair (i < j), and the stable time
// step from the summed stiffness bounds.
//
// Order of the sums (so that results do not depend on the thread count): for particle i,
//   total_i = upper_i + lower_i,
// upper_i the sum over its neighbours j > i in ascending j, lower_i the sum (from zero) over its neighbours
// k < i in ascending k of what pair (k, i) gives i. One thread adds lower_i while visiting the rows in
// ascending order; several threads store each pair's share for its upper particle and gather it afterwards.
// Both evaluate the same expressions in the same order, so the bits are the same (forces.cpp is compiled
// without floating-point contraction, so an inlined expression cannot become an FMA in one path only).
#include "surfeledit/core/particles/forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "surfeledit/core/particles/repulsion.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

// On x86-64 the two block loops are also compiled for AVX2 and picked at run time. Without contraction
// (see above) every lane computes the same IEEE operations at any vector width, so the bits do not change.
// Not in sanitizer builds: the clones' ifunc resolvers run before the sanitizer runtime is up and crash.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(__SANITIZE_THREAD__) && \
    !defined(__SANITIZE_ADDRESS__)
#define SURFELEDIT_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define SURFELEDIT_SIMD_CLONES
#endif

constexpr int kLanes = 64;  // pairs evaluated together: one row's upper neighbours, in blocks
constexpr int kPad = 4;     // lanes evaluated in multiples of this (divides kLanes)

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
SURFELEDIT_SIMD_CLONES void radial_terms(const ParticleParams& p, PairBlock& b) {
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
  explicit PairCoefficients(const ParticleParams& p)
      : aP(p.alpha_planarity),
        aN(2.0 * p.alpha_normality),
        aC(2.0 * p.alpha_circularity),
        aR(p.repulsion.kind == RepulsionKind::None ? 0.0 : 2.0 * p.alpha_repulsion),
        keep_dphi(p.drop_dphi ? 0.0 : 1.0) {}
};
[[gnu::always_inline]] inline void pair_lane(const PairCoefficients& a, double nix, double niy, double niz, const WeightSample& w, double rho,
                      double e_rep, double d1_rep, double k_rep, PairBlock& b, int l) {
  const double aP = a.aP, aN = a.aN, aC = a.aC, aR = a.aR;
  const double rx = b.rx[l], ry = b.ry[l], rz = b.rz[l], njx = b.njx[l], njy = b.njy[l], njz = b.njz[l];
  const double phi = w.phi, dr = a.keep_dphi * w.dphi_r;
  const double ai = nix * rx + niy * ry + niz * rz, aj = njx * rx + njy * ry + njz * rz;  // Phi_P: n . r
  const double bx = nix - njx, by = niy - njy, bz = niz - njz, bn = bx * bx + by * by + bz * bz;  // Phi_N
  const double c = (nix + njx) * rx + (niy + njy) * ry + (niz + njz) * rz;  // Phi_C: (n_i + n_j) . r
  b.e[l] = aP * (ai * ai * phi + aj * aj * phi) + aN * (bn * phi) + aC * (c * c * phi) + aR * e_rep;
  const double rc = aP * (ai * ai * dr + aj * aj * dr) + aN * (bn * dr) + aC * (c * c * dr) + aR * d1_rep;
  const double ci = aP * (2.0 * ai * phi) + aC * (2.0 * c * phi), cj = aP * (2.0 * aj * phi) + aC * (2.0 * c * phi);
  const double tn = aN * (2.0 * phi);
  b.k[l] = aP * (2.0 * projection_stiffness(1.0, rho, w)) + aN * conormality_stiffness(bn, w) +
           aC * projection_stiffness(2.0, rho, w) + aR * k_rep;
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
SURFELEDIT_SIMD_CLONES void pair_kernel(const ParticleParams& p, const Vec3& ni, PairBlock& b) {
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
SURFELEDIT_SIMD_CLONES void compact_kernel(const ParticleParams& p, const Vec3& ni, PairBlock& b) {
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

// First entry of row i with a neighbour above i (rows ascending).
inline std::int64_t upper_begin(const Neighbourhood& nb, Index i) {
  const auto begin = nb.indices.begin();
  return std::upper_bound(begin + nb.offsets[i], begin + nb.offsets[i + 1], i) - begin;
}

}  // namespace

void compute_forces(const ParticleState& s, const Neighbourhood& nb, const ParticleParams& p, SystemForces& out) {
  const Index n = s.size();
  out.force.setZero(n, 3);
  out.torque.setZero(n, 3);
  out.stiffness.setZero(n);
  out.normals.resize(n, 3);
  for (Index i = 0; i < n; ++i) out.normals.row(i) = s.normal(i).transpose();
  Values& energy = out.pair_energy;
  energy.setZero(n);
  const Points& normals = out.normals;
  const int threads = resolve_threads(p.threads);

  // The upper sums of row i (f, t_i, k; E into energy[i]); `lower(j, c, b, l)` takes lane l's share for
  // j (entry c). `b` is the caller's (per thread) block.
  struct Upper {
    Vec3 f, t;
    double k;
  };
  // Accumulated as scalars: as Vec3 the compiler adds (x, y) as one vector load of two just-stored lanes,
  // which cannot be store-forwarded and stalled every lane (half of compute_forces' own time in perf).
  const bool compact = p.weight.kind == WeightKind::Compact &&
                       (p.repulsion.kind == RepulsionKind::Weight || p.repulsion.kind == RepulsionKind::None);
  const double far = 2.0 * p.weight.radius;  // padding lanes: out of range, so they give zeros
  const double* x = s.x.data();               // row-major #P by 3
  const double* nrm = normals.data();
  const std::int64_t* offsets = nb.offsets.data();
  const Index* indices = nb.indices.data();
  const auto row = [&](Index i, PairBlock& b, auto&& lower) {
    const double xix = x[3 * i], xiy = x[3 * i + 1], xiz = x[3 * i + 2];
    const Vec3 ni(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]);
    double fx = 0.0, fy = 0.0, fz = 0.0, tx = 0.0, ty = 0.0, tz = 0.0, k = 0.0, e = 0.0;
    for (std::int64_t c0 = upper_begin(nb, i), end = offsets[i + 1]; c0 < end; c0 += kLanes) {
      const int count = static_cast<int>(std::min<std::int64_t>(kLanes, end - c0));
      const Index* js = indices + c0;
      for (int l = 0; l < count; ++l) {
        const double* xj = x + 3 * js[l];
        const double* nj = nrm + 3 * js[l];
        b.rx[l] = xj[0] - xix, b.ry[l] = xj[1] - xiy, b.rz[l] = xj[2] - xiz;
        b.njx[l] = nj[0], b.njy[l] = nj[1], b.njz[l] = nj[2];
      }
      // Whole vectors only: a scalar remainder of this kernel costs as much as several vectors.
      b.size = (count + kPad - 1) / kPad * kPad;
      for (int l = count; l < b.size; ++l) {
        b.rx[l] = far, b.ry[l] = 0.0, b.rz[l] = 0.0;
        b.njx[l] = 0.0, b.njy[l] = 0.0, b.njz[l] = 1.0;
      }
      if (compact) {
        compact_kernel(p, ni, b);
      } else {
        radial_terms(p, b);
        pair_kernel(p, ni, b);
      }
      for (int l = 0; l < count; ++l) {
        fx += b.fx[l], fy += b.fy[l], fz += b.fz[l];
        tx += b.tix[l], ty += b.tiy[l], tz += b.tiz[l];
        k += b.k[l];
        e += b.e[l];
        lower(js[l], c0 + l, b, l);
      }
    }
    energy[i] = e;
    return Upper{Vec3(fx, fy, fz), Vec3(tx, ty, tz), k};
  };

  if (threads == 1) {
    // out.* of row j hold lower_j (complete once the rows below j are done) until row j adds upper_j.
    PairBlock b;
    double* force = out.force.data();
    double* torque = out.torque.data();
    double* stiffness = out.stiffness.data();
    for (Index i = 0; i < n; ++i) {
      const Upper up = row(i, b, [&](Index j, std::int64_t, const PairBlock& pb, int l) {
        double* f = force + 3 * j;
        double* t = torque + 3 * j;
        f[0] -= pb.fx[l], f[1] -= pb.fy[l], f[2] -= pb.fz[l];
        t[0] += pb.tjx[l], t[1] += pb.tjy[l], t[2] += pb.tjz[l];
        stiffness[j] += pb.k[l];
      });
      out.force.row(i) = up.f.transpose() + out.force.row(i);
      out.torque.row(i) = up.t.transpose() + out.torque.row(i);
      out.stiffness[i] = up.k + out.stiffness[i];
    }
  } else {
    // Pair shares at the upper entry (i < j) of row i; mirror[c] of a lower entry (row j, neighbour k < j)
    // is the entry of j in row k.
    const std::size_t entries = nb.indices.size();
    out.pair_force.setZero(static_cast<Eigen::Index>(entries), 3);
    out.pair_torque.setZero(static_cast<Eigen::Index>(entries), 3);
    out.pair_stiffness.setZero(static_cast<Eigen::Index>(entries));
    std::vector<std::int64_t>& mirror = out.mirror;
    mirror.assign(entries, 0);
    std::vector<std::int64_t> cursor(nb.offsets.begin(), nb.offsets.end() - 1);
    for (Index i = 0; i < n; ++i)
      for (std::int64_t c = upper_begin(nb, i); c < nb.offsets[i + 1]; ++c) {
        const Index j = nb.indices[c];
        if (cursor[j] >= nb.offsets[j + 1] || nb.indices[cursor[j]] != i)
          throw Error(ErrorCode::InvalidArgument, "neighbourhood", "not symmetric: j in N(i) but i not in N(j)");
        mirror[cursor[j]++] = c;
      }
    for (Index j = 0; j < n; ++j)
      if (cursor[j] != upper_begin(nb, j))
        throw Error(ErrorCode::InvalidArgument, "neighbourhood", "not symmetric: i in N(j) but j not in N(i)");
#pragma omp parallel num_threads(threads)
    {
      PairBlock b;
#pragma omp for schedule(static)
      for (Index i = 0; i < n; ++i) {
        const Upper up = row(i, b, [&](Index, std::int64_t c, const PairBlock& pb, int l) {
          out.pair_force.row(c) << pb.fx[l], pb.fy[l], pb.fz[l];
          out.pair_torque.row(c) << pb.tjx[l], pb.tjy[l], pb.tjz[l];
          out.pair_stiffness[c] = pb.k[l];
        });
        out.force.row(i) = up.f.transpose();
        out.torque.row(i) = up.t.transpose();
        out.stiffness[i] = up.k;
      }
#pragma omp for schedule(static)
      for (Index j = 0; j < n; ++j) {
        Vec3 f = Vec3::Zero(), t = Vec3::Zero();
        double k = 0.0;
        for (std::int64_t c = nb.offsets[j]; c < nb.offsets[j + 1] && nb.indices[c] < j; ++c) {
          f -= out.pair_force.row(mirror[c]).transpose();
          t += out.pair_torque.row(mirror[c]).transpose();
          k += out.pair_stiffness[mirror[c]];
        }
        out.force.row(j) = out.force.row(j) + f.transpose();
        out.torque.row(j) = out.torque.row(j) + t.transpose();
        out.stiffness[j] = out.stiffness[j] + k;
      }
    }
  }
  out.energy = energy.sum();
}

double stable_time_step(const SystemForces& forces, const Values& scale, const ParticleParams& p) {
  double lambda = 0.0, s_max = 0.0;
  for (Eigen::Index i = 0; i < forces.stiffness.size(); ++i) {
    lambda = std::max(lambda, 2.0 * scale[i] * forces.stiffness[i]);
    s_max = std::max(s_max, scale[i]);
  }
  const double b = s_max * std::max(p.damping, p.angular_damping);
  if (lambda == 0.0 && b == 0.0) return std::numeric_limits<double>::infinity();
  // Damped symplectic step x'' = -lambda x - b x' is stable for lambda h^2 + 2 b h < 4.
  return p.dt_safety * 4.0 / (b + std::sqrt(b * b + 4.0 * lambda));
}

}  // namespace surfeledit
