// Normals of a point set that has none (a text or PLY point set, an OBJ without faces): PCL's PCA estimate over
// the k nearest neighbours, oriented consistently by a minimum spanning tree (Hoppe et al. 1992).
#pragma once

#include <string>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

// Unit normals (#P by 3) of the points `p` (#P by 3) from their `k` nearest neighbours, oriented outward from the
// highest point of each connected part. Throws Error(InvalidArgument, "path") naming `path` for fewer than 3 points.
Points estimate_normals(const Points& p, int k, const std::string& path);

}  // namespace surfeledit
