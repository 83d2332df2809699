// The blend tool (thesis §12.3, docs/particles.md "Blend"): the surfels within a range of the feature
// surfels become oriented particles, the surfels just beyond them are the rigid region, the particle system
// runs for a number of iterations, and the particles become surfels again.
//
// The system runs in spacing units: positions are shifted to the blend region's centroid and divided by
// the model's mean radius, so that dt, the neighbourhood factor and the force amplitudes mean the same on
// every model (a model scaled by 1e-4 or 1e4 blends the same way).
#pragma once

#include <vector>

#include "surfeledit/core/particles/params.hpp"
#include "surfeledit/core/particles/projection.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct BlendParams {
  int iterations = 50;            // iterations of dt each, >= 0
  double range_factor = 4.0;      // f: the blend region is every surfel within f x mean radius of a feature
                                  // surfel (§12.3.1), > 0
  double neighbour_factor = 3.6;  // f_N: neighbourhood radius = f_N x mean radius (§12.3.3; 3.6 gives about 40
                                  // neighbours on an evenly sampled surface), > 0
  double dt = 0.1;                // time step per iteration in spacing units (thesis: 0.1); sub-stepped when
                                  // above the stable step
  RepulsionKind repulsion = RepulsionKind::Weight;  // repulsion potential (§12.2.4)
  WeightKind weight = WeightKind::Compact;          // weighting function (§12.2.5)
  bool only_grow = false;         // move only along +n (§12.3.6)
  bool adaptive = false;          // local adaptive repulsion: split below split_below, kill above kill_above
                                  // neighbours (§12.3.7); needs recomputed neighbourhoods (grid) when on
  NeighbourMode neighbours = NeighbourMode::Cached;  // cached or recomputed every iteration
  double gamma = 2.0;             // region scaling exponent (Eq. 12.28), >= 0
  double spring_r0 = 1.0;         // Spring repulsion: equilibrium distance in mean radii, > 0
  ProjectionKind projection = ProjectionKind::Mls;  // at the end: onto the MLS surface of the particles and
                                                    // the rigid region (smooths the particles' jitter, §12.3.7)
  double mls_width = 1.5;         // MLS kernel width h in mean radii (samples within 3 h count), > 0
  int split_below = 12;           // adaptive: fewer neighbours -> split, >= 1
  int kill_above = 80;            // adaptive: more neighbours -> die, > split_below
  int threads = 0;                // worker threads (0 = all); the result does not depend on it
};

// Throws InvalidArgument naming the field and the value.
void validate(const BlendParams& params);

// What replaces the repulsion when the blend region is open (after a boolean, §12.4.1: a pure repulsion
// drives the particles of an open region apart).
enum class OpenRegionForce : std::uint8_t {
  AsRequested = 0,  // the repulsion blend() was asked for
  Spring = 1,       // a spring (r0 = spring_r0 mean radii), which attracts lost particles (thesis's advice)
  None = 2,         // no repulsion at all (the thesis's two-planes example)
};
constexpr EnumNames<OpenRegionForce, 3> names_of(OpenRegionForce) {
  return {{{OpenRegionForce::AsRequested, "as_requested"}, {OpenRegionForce::Spring, "spring"},
           {OpenRegionForce::None, "none"}}};
}

// The session settings of the blend tool (settings table rows blend_*).
struct BlendSettings {
  double neighbour_factor = 3.6;  // f_N: neighbourhood radius in mean radii (BlendParams::neighbour_factor)
  double gamma = 2.0;             // region scaling exponent
  OpenRegionForce open_region = OpenRegionForce::Spring;  // repulsion of an open blend region (after a boolean)
  double spring_r0 = 1.6;         // equilibrium distance of that spring, mean radii
};

// The particle settings a blend runs with (spacing units).
ParticleParams blend_particle_params(const BlendParams& params);

struct BlendRegion {
  IndexList rows;   // blend region rows of the model, ascending (the particles, in this order)
  IndexList rigid;  // rows just beyond it (within twice the range of a feature), ascending
};

// `features`: rows of `model` (need not be sorted); range = range_factor x the model's mean radius.
BlendRegion blend_region(const SurfelModel& model, const IndexList& features, double range_factor);

struct BlendRun {
  Points positions;                  // #Q by 3 final particles (model units)
  Points normals;                    // #Q by 3 unit
  std::vector<std::int64_t> origin;  // #Q: index k into region.rows of the surfel the particle comes from
                                     // (>= 0), or -1 - k for a particle split off it
  Values energy;                     // per iteration: the system's energy before it (spacing units)
  int substeps = 0;                  // sub-steps over all iterations
};

// Runs the particle system on `positions` / `normals` (#P by 3, model units: the blend region's surfels, as
// they should start), anchored by `rigid` (#R by 3, model units); `mean_radius` sets the spacing unit.
// `rigid_normals` (#R by 3, or empty): with them the final MLS projection also fits the rigid region.
BlendRun run_blend(const Points& positions, const Points& normals, const Points& rigid, double mean_radius,
                   const BlendParams& params, const Points& rigid_normals = Points());

}  // namespace surfeledit
