// A Verlet list for recomputed neighbourhoods (thesis §12.3.3 "recomputed every iteration"): the grid's
// neighbourhood at radius + skin is kept while no particle has moved farther than skin / 2 from where it
// was when that list was built; every call filters the exact radius neighbourhood out of it. Two particles
// within `radius` now were within radius + skin then, so the result equals a fresh range query
// (neighbours_grid) every time, only cheaper while the particles move little.
#pragma once

#include "surfeledit/core/particles/neighbours.hpp"

namespace surfeledit {

struct VerletList {
  Points anchor;          // #P by 3: positions when `wide` was built (empty = never built)
  double radius = 0.0;    // the radius and skin `wide` was built for (model units)
  double skin = 0.0;
  Neighbourhood wide;     // neighbours within radius + skin of the anchors
  GridWorkspace grid;     // the grid builder's buffers
  long rebuilds = 0;      // how many times `wide` was built (for tests and benchmarks)
};

// The neighbourhood of `points` (#P by 3) at `radius` into `out` (the same lists as neighbours_grid).
// `skin` >= 0 (model units; 0 = a grid query every call). Rebuilds `list` when the particle count, radius or
// skin changed or some particle moved skin / 2 or more since the last build.
void neighbours_verlet(const Points& points, double radius, double skin, int threads, VerletList& list,
                       Neighbourhood& out);

}  // namespace surfeledit
