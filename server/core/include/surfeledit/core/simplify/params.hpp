// Settings of surface simplification (docs/algorithms.md §6, thesis §9.2): which clustering, how large a
// cluster may grow and how much it may bend, and how approximate collision detection (thesis §9.3) decides
// to look at the original surfels of a cluster.
#pragma once

#include <cstdint>
#include <string>

#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

// How the surfels are grouped into clusters (each cluster becomes one simplified surfel).
enum class SimplifyMethod : std::uint8_t {
  None = 0,           // no simplification: every surfel is its own cluster
  RegionGrowing = 1,  // thesis §9.2.1: a surfel and its k nearest form a cluster if none of them is taken yet
  Hierarchical = 2,   // thesis §9.2.2: split at the centroid, normal to the largest-variance axis, top-down
};

constexpr EnumNames<SimplifyMethod, 3> names_of(SimplifyMethod) {
  return {{{SimplifyMethod::None, "none"},
           {SimplifyMethod::RegionGrowing, "region_growing"},
           {SimplifyMethod::Hierarchical, "hierarchical"}}};
}
// Throws InvalidArgument naming `field` for a name not in names_of.
inline SimplifyMethod parse_simplify_method(const std::string& name, const std::string& field = "simplify") {
  return parse_enum<SimplifyMethod>(name, field);
}
inline const char* to_string(SimplifyMethod method) { return enum_name(method); }

struct SimplifyParams {
  SimplifyMethod method = SimplifyMethod::Hierarchical;  // clustering used (the thesis prefers hierarchical, §9.5)
  int cluster_size = 18;        // surfels per cluster: region growing takes this many (k, the surfel included);
                                // hierarchical splits until a cluster holds at most this many; >= 1.
                                // Also the degree of the region-growing sphere tree before it is made binary.
  double max_variation = 1.0;   // sigma_max in [0, 1]: a cluster's surface variation must not exceed it
                                // (hierarchical: split further; region growing: fewer neighbours taken).
                                // Variation is at most 1/3, so >= 1/3 means "size bound only".
  double member_margin = 1.0;   // approximate detection: the members of a cluster are tested when its
                                // simplified surfel collides, or when the simplified surfel is closer to the
                                // zero region than member_margin x the cluster's radius (0 = the thesis: only
                                // colliding simplified surfels, plus members that still collide)
  int threads = 0;              // worker threads for per-surfel work (0 = all); results do not depend on it
};

// Throws InvalidArgument naming the field (e.g. "cluster_size") and the value.
void validate(const SimplifyParams& params);

}  // namespace surfeledit
