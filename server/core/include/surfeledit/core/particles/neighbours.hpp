// Neighbourhoods of the particles (thesis §12.3.3): every other particle within distance `radius`, in CSR
// form, ascending by index (so sums over them, and results, do not depend on the structure that found them).
// Cached: one query at the start; recomputed: a new query every iteration (uniform grid or k-d tree).
#pragma once

#include <cstdint>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

struct Neighbourhood {
  std::vector<std::int64_t> offsets;  // #P + 1; neighbours of i are indices[offsets[i] .. offsets[i+1])
  IndexList indices;                  // never i itself
  Index size() const { return offsets.empty() ? 0 : static_cast<Index>(offsets.size() - 1); }
  Index count(Index i) const { return static_cast<Index>(offsets[i + 1] - offsets[i]); }
};

// `points` #P by 3; `threads` as everywhere in the core (0 = all); the result does not depend on it.
Neighbourhood neighbours_kdtree(const Points& points, double radius, int threads = 0);
// Uniform grid with cells of at least `radius` (coarser when the bounding box would need too many cells).
Neighbourhood neighbours_grid(const Points& points, double radius, int threads = 0);

// The grid builder's buffers, kept between calls (a recomputed neighbourhood reuses them every iteration).
struct GridWorkspace {
  std::vector<std::int64_t> cell;    // #P: cell of every particle
  std::vector<std::int64_t> start;   // #cells + 1: first sorted slot of every cell
  std::vector<std::int64_t> fill;    // #cells: counting-sort cursors
  IndexList sorted;                  // #P: particles by cell
  std::vector<double> sp;            // #P * 3: their coordinates in that order
  std::vector<IndexList> found;      // per block of rows: neighbours in cell order
  std::vector<std::int64_t> cursor;  // #P: transpose cursors
};
// The same lists as neighbours_grid, into `out`, reusing `ws` and `out`'s storage.
void neighbours_grid(const Points& points, double radius, int threads, GridWorkspace& ws, Neighbourhood& out);

}  // namespace surfeledit
