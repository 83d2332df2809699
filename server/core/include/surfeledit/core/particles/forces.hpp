// Total forces, torques, energy and stiffness of the particle system (thesis Eq. 12.5-12.9): the sum over
// neighbour pairs of E_ij = 2 a_R Phi_R + a_P (Phi_P(n_i) + Phi_P(n_j)) + 2 a_N Phi_N + 2 a_C Phi_C,
// i.e. the thesis's energy summed over ordered pairs; forces and torques are its exact negative gradients
// (unless drop_dphi). Damping and region scaling are applied by the integrator.
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/particles/neighbours.hpp"
#include "surfeledit/core/particles/params.hpp"
#include "surfeledit/core/particles/state.hpp"

namespace surfeledit {

struct SystemForces {
  Points force;      // #P by 3, on each particle (without damping)
  Points torque;     // #P by 3
  Values stiffness;  // #P: sum over neighbours of the pair stiffness bounds (docs/particles.md)
  double energy = 0.0;  // sum over unordered pairs of E_ij

  // Workspace of compute_forces, kept so that repeated calls do not allocate.
  Values pair_energy;                // #P: sum of E_ij over the neighbours j > i
  std::vector<double> particles;     // 8 (#P + 1): per particle (x, y, z, 0, nx, ny, nz, 0), then padding
  std::vector<double> lower;         // 8 (#P + 1), threads == 1: running sums of the lower pairs' shares
  std::vector<double> shares;        // 8 #E (E neighbour entries), threads > 1: share of pair (i, j),
                                     // i < j, for j at its entry in row i: (-f, k, t_j, 0)
  std::vector<std::int64_t> mirror;  // #E, threads > 1: entry of j in row i for the entry of i in row j
};

// The compiled variants of compute_forces' pair loop; all give the same bits (no FMA contraction).
enum class ForcePath : std::uint8_t {
  Auto = 0,      // the widest the CPU runs
  Baseline = 1,  // the build's baseline instruction set (x86-64: SSE2)
  Avx2 = 2,      // x86-64 with AVX2 (Conflict("path") where the CPU or the build lacks it)
};
bool force_path_available(ForcePath path);

// Each unordered pair is evaluated once; `nbrs` must be symmetric (j in N(i) exactly when i in N(j), as
// both neighbourhood builders give; with threads > 1 InvalidArgument otherwise). The sums run in a fixed
// order, so the result does not depend on the thread count.
void compute_forces(const ParticleState& state, const Neighbourhood& nbrs, const ParticleParams& params,
                    SystemForces& out, ForcePath path = ForcePath::Auto);

// Largest time step the stiffness bound allows (Gershgorin bound on the scaled Hessian, damped symplectic
// step), times params.dt_safety; +inf when nothing interacts. `scale` #P region scale factors.
double stable_time_step(const SystemForces& forces, const Values& scale, const ParticleParams& params);

}  // namespace surfeledit
