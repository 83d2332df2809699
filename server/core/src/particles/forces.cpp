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

// One unordered pair, r = x_j - x_i: the force on i (-f on j, Newton's third law holds exactly for every
// term), the torques on i and on j (not antisymmetric), the stiffness bound (the same at both ends) and
// E_ij = 2 a_R Phi_R + a_P (Phi_P(n_i) + Phi_P(n_j)) + 2 a_N Phi_N + 2 a_C Phi_C.
struct PairForces {
  Vec3 f, ti, tj;
  double k, e;
};

// The terms of potentials.hpp and repulsion.hpp written out with the common factors shared: false when
// the weight (and so every term) is zero.
inline bool pair_forces(const Vec3& r, const Vec3& ni, const Vec3& nj, const ParticleParams& p, PairForces& o) {
  const double rho = r.norm();
  const WeightSample w = weight(p.weight, rho);
  if (w.phi == 0.0 && w.dphi == 0.0) return false;
  const double phi = w.phi, dphi_r = p.drop_dphi ? 0.0 : w.dphi_r;
  double rc = 0.0, ci = 0.0, cj = 0.0, tn = 0.0;  // f = rc r + ci n_i + cj n_j; t_i = ci r x n_i + tn n_i x n_j
  o.k = o.e = 0.0;
  if (p.alpha_planarity > 0.0) {  // Phi_P(n_i) + Phi_P(n_j), a = n . r
    const double a = p.alpha_planarity, ai = ni.dot(r), aj = nj.dot(r);
    o.e += a * (ai * ai * phi + aj * aj * phi);
    rc += a * (ai * ai * dphi_r + aj * aj * dphi_r);
    ci += a * (2.0 * ai * phi);
    cj += a * (2.0 * aj * phi);
    o.k += a * (2.0 * projection_stiffness(1.0, rho, w));
  }
  if (p.alpha_normality > 0.0) {  // Phi_N, b = |n_i - n_j|^2
    const double a = 2.0 * p.alpha_normality, b = (ni - nj).squaredNorm();
    o.e += a * (b * phi);
    rc += a * (b * dphi_r);
    tn += a * (2.0 * phi);
    o.k += a * conormality_stiffness(b, w);
  }
  if (p.alpha_circularity > 0.0) {  // Phi_C, c = (n_i + n_j) . r; the same factor 2 c phi moves both normals
    const double a = 2.0 * p.alpha_circularity, c = (ni + nj).dot(r);
    o.e += a * (c * c * phi);
    rc += a * (c * c * dphi_r);
    ci += a * (2.0 * c * phi);
    cj += a * (2.0 * c * phi);
    o.k += a * (projection_stiffness(2.0, rho, w));
  }
  if (p.alpha_repulsion > 0.0 && p.repulsion.kind != RepulsionKind::None) {
    const double a = 2.0 * p.alpha_repulsion;
    const RadialTerm t = repulsion_radial(p.repulsion, rho, w);
    o.e += a * t.energy;
    rc += a * t.d1_r;
    o.k += a * t.stiffness;
  }
  // Torques: -grad over a rotation of i is (dPhi/dn_i) x n_i; for j the same with r -> -r.
  const Vec3 nn = tn * ni.cross(nj);
  o.f = rc * r + ci * ni + cj * nj;
  o.ti = ci * r.cross(ni) + nn;
  o.tj = cj * r.cross(nj) - nn;
  return true;
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

  // The upper sums of row i; `lower(j, c, pf)` takes pair (i, j)'s share for j, stored at entry c.
  const auto row = [&](Index i, auto&& lower) {
    const Vec3 xi = s.x.row(i).transpose(), ni = normals.row(i).transpose();
    Vec3 f = Vec3::Zero(), ti = Vec3::Zero();
    double k = 0.0, e = 0.0;
    PairForces pf;
    for (std::int64_t c = upper_begin(nb, i); c < nb.offsets[i + 1]; ++c) {
      const Index j = nb.indices[c];
      if (!pair_forces(s.x.row(j).transpose() - xi, ni, normals.row(j).transpose(), p, pf)) continue;
      f += pf.f;
      ti += pf.ti;
      k += pf.k;
      e += pf.e;
      lower(j, c, pf);
    }
    energy[i] = e;
    return PairForces{f, ti, Vec3::Zero(), k, e};
  };

  if (threads == 1) {
    // out.* of row j hold lower_j (complete once the rows below j are done) until row j adds upper_j.
    for (Index i = 0; i < n; ++i) {
      const PairForces up = row(i, [&](Index j, std::int64_t, const PairForces& pf) {
        out.force.row(j) -= pf.f.transpose();
        out.torque.row(j) += pf.tj.transpose();
        out.stiffness[j] += pf.k;
      });
      out.force.row(i) = up.f.transpose() + out.force.row(i);
      out.torque.row(i) = up.ti.transpose() + out.torque.row(i);
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
#pragma omp for schedule(static)
      for (Index i = 0; i < n; ++i) {
        const PairForces up = row(i, [&](Index, std::int64_t c, const PairForces& pf) {
          out.pair_force.row(c) = pf.f.transpose();
          out.pair_torque.row(c) = pf.tj.transpose();
          out.pair_stiffness[c] = pf.k;
        });
        out.force.row(i) = up.f.transpose();
        out.torque.row(i) = up.ti.transpose();
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
