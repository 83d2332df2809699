// Session settings by name: the names the protocol's OP_CONFIGURE and the Python keyword
// arguments use (`session.configure(algorithm="robust", boundary_n=10, ...)`).
//
//   algorithm        text    "none" | "simple" | "improved" | "temporal" | "robust"
//   threshold        number  W of the inside test, model units
//   boundary         bool    boundary-surfel heuristic (simple/improved/temporal)
//   boundary_n       int     neighbours looked at for boundary marks
//   boundary_i       int     zero neighbours marked boundary
//   step_bound       bool    per-surfel step bound (simple/improved/temporal)
//   sphere_margin    number  temporal/robust spheres shrink by this many radii of the nearest surfel
//   threads          int     worker threads for detection (0 = all)
//   resample         bool    dynamic resampling
//   split_threshold  number  stretch ratio that splits a surfel
//   knn_eps          number  approximate nearest-surfel search (nanoflann eps, >= 0; 0 = exact)
//   zero_hierarchy   text    "none" | "aabb" | "obb" | "sphere" | "sphere_hierarchical" | "sphere_incremental":
//                            tree over the zero region (hierarchy.hpp; sphere_* = sphere cluster trees)
//   deformable_hierarchy text "none" | "aabb": tree over the deformable region (needs zero_hierarchy)
//   update           text    "bottom_up" | "top_down" | "hybrid": refit of the deformable tree
//   hybrid_f         number  hybrid: fraction of the levels refit bottom-up, [0, 1]
//   sat              text    "lite" | "full": OBB/AABB overlap test
//   extended         bool    narrow phase against the original model (needs algorithm robust)
//   leaf_max_surfels int     a tree node with at most this many surfels is a leaf
//   leaf_min_surfels int     no split leaves a child with fewer surfels
//   max_level        int     deepest tree level (root = 0)
//   min_leaf_extent  number  leaf boxes at least this wide per axis, model units
//   inflation        number  margin added to a box when a refit recomputes it, model units
//   simplify         text    "none" | "region_growing" | "hierarchical": approximate detection on clusters of
//                            the deformable region (simplify/approximate_detector.hpp; simple/temporal/robust,
//                            no hierarchy)
//   cluster_size     int     surfels per cluster, >= 1 (1 = the exact result); also the leaves of sphere_* trees
//   max_variation    number  largest surface variation of a cluster, [0, 1]; also for sphere_* trees
//   member_margin    number  approximate detection: members tested within this many cluster radii of the zero region
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/resampling.hpp"
#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {

struct SessionSettings {
  CollisionParams collision;
  ResampleParams resample;
  HierarchyParams hierarchy;
  SimplifyParams simplify = no_simplification();  // clustering (approximate detection when method != None;
                                                  // cluster_size / max_variation also shape sphere_* trees)

  static SimplifyParams no_simplification() {
    SimplifyParams p;
    p.method = SimplifyMethod::None;
    return p;
  }
};

// A setting's value as it arrives: number (also for ints), bool or text.
using SettingValue = std::variant<double, bool, std::string>;
struct NamedSetting {
  std::string name;
  SettingValue value;
};

// Applies `changes` to a copy of `current` and validates the result. Throws InvalidArgument naming
// the setting (field = its name) for an unknown name, a value of the wrong kind (e.g. text for
// boundary_n, 2.5 for an int) or a bad value; `current` is never modified.
SessionSettings apply_settings(const SessionSettings& current, const std::vector<NamedSetting>& changes);

// Every setting with its current value, in the order listed above.
std::vector<NamedSetting> describe(const SessionSettings& settings);

}  // namespace surfeledit
