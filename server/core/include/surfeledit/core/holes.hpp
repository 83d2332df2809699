// Hole filling (thesis §12.4.2, docs/particles.md "Hole filling"): boundary surfels (a large angular gap
// among their nearest neighbours, seen in their tangent plane) grouped into loops; a loop no wider than
// max_diameter is a hole. Particles are seeded across it at the surrounding density on the quadric height
// field fitted to the surfels around it, diffuse with the particle engine (repulsion, local adaptive split /
// kill) while kept on that quadric, are projected onto the MLS surface of the ring and themselves (optional),
// and become surfels where no surfel covers the surface yet.
#pragma once

#include <vector>

#include "surfeledit/core/particles/projection.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct HoleParams {
  double max_diameter = 0.0;  // loops wider than this (model units) are open borders, left alone; > 0
  int iterations = 10;        // particle iterations per hole, >= 0
  int neighbours = 12;        // k nearest surfels of the angular-gap test, >= 4
  double gap_angle = 1.9;     // radians: a surfel whose neighbours leave a larger gap is a boundary surfel,
                              // in (0, 2 pi)
  double link_factor = 2.5;   // boundary surfels closer than this x their mean radius are in one loop, > 0
  int min_loop = 6;           // loops with fewer boundary surfels are noise, not holes, >= 3
  double ring_factor = 3.0;   // the quadric is fitted to the surfels within this x radius of the loop, > 0
  ProjectionKind projection = ProjectionKind::Mls;  // at the end: onto the MLS surface of the ring surfels and
                                                    // the particles (tangent: stay on the fitted quadric)
  double mls_width = 1.5;     // MLS kernel width h in mean radii of the loop (samples within 3 h count), > 0
  int threads = 0;            // worker threads (0 = all); the result does not depend on it
};

// Throws InvalidArgument naming the field.
void validate(const HoleParams& params);

struct Hole {
  IndexList boundary;     // rows of the boundary surfels, ascending
  double diameter = 0.0;  // largest distance between two of them (model units)
};

// Rows of the boundary surfels, ascending.
IndexList boundary_rows(const SurfelModel& model, const HoleParams& params);
// The loops of `boundary` (rows), by link distance; every loop with at least min_loop surfels, ordered by
// their smallest row.
std::vector<Hole> group_loops(const SurfelModel& model, const IndexList& boundary, const HoleParams& params);

struct HoleFilling {
  Points positions;  // #Q by 3 new surfels (model units)
  Points normals;    // #Q by 3 unit, oriented as the surfels around the hole
  Values radii;      // #Q
  IndexList parent;  // #Q: the boundary row nearest to each (colours, tangents)
};

// Fills one hole of `model` (its boundary rows); an empty result when nothing is uncovered.
HoleFilling fill_hole(const SurfelModel& model, const Hole& hole, const HoleParams& params);

}  // namespace surfeledit
