// The simplified surfel of a cluster (thesis §9.2): one surfel standing for all of the cluster's.
#pragma once

#include <vector>

#include "surfeledit/core/simplify/clustering.hpp"

namespace surfeledit {

struct SimplifiedSurfel {
  Vec3 position = Vec3::Zero();  // centroid of the members' positions, model units
  Vec3 normal = Vec3::UnitZ();   // mean of the members' normals, re-normalised (unit)
  double radius = 0.0;           // covers every member's disc: max |p_i - position| + r_i, model units
  Index count = 0;               // members
};

// Simplified surfel of rows[0 .. n). `radii` may be empty (radius 0 per surfel). If the normals cancel
// out, the normal is the cluster's smallest-variance axis oriented like the first member's normal.
SimplifiedSurfel simplify_cluster(const Points& positions, const Points& normals, const Values& radii,
                                  const Index* rows, std::size_t n);

// One simplified surfel per cluster (multithreaded over clusters; 0 = all threads).
std::vector<SimplifiedSurfel> simplify(const Points& positions, const Points& normals, const Values& radii,
                                       const Clustering& clusters, int threads = 0);

}  // namespace surfeledit
