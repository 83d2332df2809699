// A disjoint-set forest over indices (private to the core): `parent[i] == i` at a root. Used to group boundary
// loops (holes.cpp) and inside-model boundary rows (collision/inside_model.cpp).
#pragma once

#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit::union_find {

// The root of i's set; halves the path on the way (each visited node then points to its grandparent).
inline Index find_root(std::vector<Index>& parent, Index i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace surfeledit::union_find
