// Parameters of a bounding volume hierarchy: how it is built (docs/algorithms.md §5 "Build", thesis §7.3.6,
// §10.1.1)
// and how a deforming AABB tree is kept up to date (thesis §8.3.1).
#pragma once

#include <cstdint>
#include <string>

#include "surfeledit/core/enum_names.hpp"

namespace surfeledit::bvh {

// How a deforming tree follows its surfels between rebuilds (thesis §8.3.1, Fig. 8.7).
enum class UpdateMode : std::uint8_t {
  BottomUp = 0,  // selective bottom-up refit of every node each step (per-axis masks)
  TopDown = 1,   // lazy: a node is refit from its surfels when a traversal first visits it in a step
  Hybrid = 2,    // upper hybrid_f * height levels bottom-up each step, deeper nodes top-down on visit
  Bounded = 3,   // no per-row pass: a node's box is its last fit grown by the step's largest displacement
                 // (docs/algorithms.md §5 "Bounded update"); a leaf is refit when a traversal reaches it
};
constexpr EnumNames<UpdateMode, 4> names_of(UpdateMode) {
  return {{{UpdateMode::BottomUp, "bottom_up"},
           {UpdateMode::TopDown, "top_down"},
           {UpdateMode::Hybrid, "hybrid"},
           {UpdateMode::Bounded, "bounded"}}};
}
// Throws InvalidArgument naming `field` for a name not in names_of.
inline UpdateMode parse_update(const std::string& name, const std::string& field = "update") {
  return parse_enum<UpdateMode>(name, field);
}
inline const char* to_string(UpdateMode mode) { return enum_name(mode); }

struct BvhParams {
  int max_level = 20;           // deepest level a node may have (root = level 0); nodes there are leaves
  int leaf_max_surfels = 16;    // a node with at most this many surfels is not split further
  int leaf_min_surfels = 2;     // no split makes a child with fewer surfels than this (>= 1)
  double min_leaf_extent = 0.0; // model units: each leaf box is at least this wide along each of its axes
  double inflation = 0.0;       // model units: margin added around a box whenever a refit recomputes it
  UpdateMode update = UpdateMode::Bounded;  // refit strategy of a deforming tree (AABB trees only)
  double hybrid_f = 0.5;        // Hybrid: fraction in [0, 1] of the levels (from the root) refit bottom-up
};

// Throws InvalidArgument naming the field (e.g. "leaf_min_surfels") and the value.
void validate(const BvhParams& params);

}  // namespace surfeledit::bvh
