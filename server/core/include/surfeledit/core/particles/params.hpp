// Settings of the oriented particle engine (thesis §12, docs/algorithms.md §8, docs/particles.md).
#pragma once

#include <cstdint>

#include "surfeledit/core/particles/repulsion.hpp"
#include "surfeledit/core/particles/weighting.hpp"

namespace surfeledit {

enum class ParticleIntegrator : std::uint8_t {
  Leapfrog = 0,     // Eq. 12.25-12.27: half-step velocities, damping velocity extrapolated
  EulerCromer = 1,  // first order: v += h a(x, v); x += h v
};

enum class NeighbourMode : std::uint8_t {
  Cached = 0,           // one range query at the start (uniform grid; again only after split / kill)
  RecomputeGrid = 1,    // a uniform-grid range query every iteration
  RecomputeKdTree = 2,  // a k-d tree built and queried every iteration
};
constexpr EnumNames<NeighbourMode, 3> names_of(NeighbourMode) {
  return {{{NeighbourMode::Cached, "cached"}, {NeighbourMode::RecomputeGrid, "grid"},
           {NeighbourMode::RecomputeKdTree, "kdtree"}}};
}

enum class StepPolicy : std::uint8_t {
  SubStep = 0,  // a dt above the stable step is split into equal sub-steps below it
  Refuse = 1,   // a dt above the stable step throws Conflict("dt") and changes nothing
};

struct ParticleParams {
  WeightParams weight;              // phi and the neighbourhood radius d
  RepulsionParams repulsion;        // repulsion potential
  double alpha_repulsion = 1.0;     // alpha_R (Eq. 12.8), >= 0
  double alpha_planarity = 1.0;     // alpha_P, >= 0
  double alpha_normality = 1.0;     // alpha_N, >= 0
  double alpha_circularity = 1.0;   // alpha_C, >= 0
  bool drop_dphi = false;           // true = the thesis's forces without the phi' terms (not exact gradients)
  double damping = 1.0;             // beta_0: linear damping (per unit time), >= 0
  double angular_damping = 1.0;     // beta_1: angular damping, >= 0
  double gamma = 2.0;               // region scaling exponent, s_i = (d_i / max d)^gamma (Eq. 12.28), >= 0
  ParticleIntegrator integrator = ParticleIntegrator::Leapfrog;  // time integration
  double dt = 0.1;                  // time step h per iteration (the thesis used 0.1), > 0
  StepPolicy policy = StepPolicy::SubStep;  // what a dt above the stable step does
  double dt_safety = 0.9;           // the stable step is this fraction of the bound, in (0, 1]
  int max_substeps = 256;           // SubStep: more would be needed -> Conflict("dt"), >= 1
  bool velocity_control = true;     // §12.3.5: zero a velocity the new force points against
  bool only_grow = false;           // §12.3.6: move only along +n
  NeighbourMode neighbours = NeighbourMode::Cached;  // how neighbourhoods are found
  double neighbour_skin = 0.1;      // RecomputeGrid: Verlet skin as a fraction of weight.radius (the exact
                                    // neighbourhood is filtered every iteration; 0 = a grid query), >= 0
  bool project_tangent = false;     // §12.3.7: after each move, onto the nearest original tangent plane
                                    // (needs the original surface, ParticleEngine::set_surface)
  int split_below = 0;              // §12.3.7: a particle with fewer neighbours splits (0 = never)
  int kill_above = 0;               // a particle with more neighbours dies (0 = never)
  int local_repulsion_steps = 5;    // relaxation steps of pure repulsion around split / killed particles
  int threads = 0;                  // worker threads (0 = all); results do not depend on it
};

// Throws InvalidArgument naming the field (e.g. "dt") and the value.
void validate(const ParticleParams& params);

}  // namespace surfeledit
