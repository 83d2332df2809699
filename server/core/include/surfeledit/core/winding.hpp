// Generalized winding number of an oriented surfel set (docs/algorithms.md §4.6): the fast
// evaluation of Barill et al. 2018 ("fast winding numbers for soups and clouds") for points.
//
//   w(q) = sum_i a_i n_i . (p_i - q) / (4 pi |p_i - q|^3)
//
// over surfels i (position p_i, unit outward normal n_i, area a_i). w is about 1 inside a closed
// surface, 0 outside, 1/2 on it; for a surface with a planar hole, w > 1/2 still means inside the
// solid the hole's cap would close (§4.6). A tree of area-weighted centroids with their summed dipoles
// a_i n_i answers far nodes (|q - c| > beta * node radius) with one dipole term and sums near leaves
// exactly; beta = 0 sums every surfel exactly.
#pragma once

#include <memory>
#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

struct WindingParams {
  double beta = 2.0;   // far-field acceptance: a node at distance > beta x its radius is one dipole (>= 0;
                       // 0 = exact sum over every surfel)
  int leaf_size = 16;  // surfels per tree leaf (>= 1)
  int area_k = 8;      // surfel_areas(): neighbours of the local density estimate (>= 1)
};

// Area per surfel from the local sample density: pi d_k^2 / (k + 1/2) with d_k the distance to the
// k-th nearest other surfel (#P): the disc of radius d_k holds the surfel, k - 1 neighbours and, half
// in, the k-th on its rim. Disc radii of splats overlap (a radius of one spacing covers about pi
// surfels' share each), so pi r^2 would overweight every surfel; the density area sums to the
// surface area. Sets of at most k surfels use their farthest surfel (k = count - 1), a single
// surfel area 0.
Values surfel_areas(const Points& positions, int k = 8);

class WindingNumber {
 public:
  // positions, normals: #P by 3 (normals unit, outward); areas: #P (>= 0, model units squared).
  // Throws InvalidArgument (field named) on mismatched sizes or non-finite values.
  WindingNumber(const Points& positions, const Points& normals, const Values& areas, WindingParams params = {});
  ~WindingNumber();
  WindingNumber(WindingNumber&&) noexcept;
  WindingNumber& operator=(WindingNumber&&) noexcept;

  // w at q (dimensionless). Thread-safe, const.
  double at(const Vec3& q) const;
  // w at q with another far-field acceptance `beta` (>= 0; 0 = exact).
  double at(const Vec3& q, double beta) const;
  // #Q queries -> #Q values, multithreaded (`threads`: 0 = all); results independent of threads.
  Values at(const Points& queries, int threads = 0) const;

  Index size() const;              // surfels in the tree
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace surfeledit
