// Dynamic resampling (docs/algorithms.md §1 "Dynamic resampling"; Pauly et al. 2003): surfels stretched by
// the deformation are split in two along their direction of greatest stretch.
//
// Stretch of a surfel: with its deformed tangent axes u, v (lengths = radii along them), the first
// fundamental form G = [u.u, u.v; v.u, v.v]; its largest semi-axis is sqrt(lambda_max(G)).
// The surfel is split when that exceeds `split_threshold` times its rest radius (its radius when
// resampling started or it was created).
#pragma once

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct ResampleParams {
  bool enabled = false;          // split stretched surfels after each deformation step
  double split_threshold = 1.5;  // split when largest semi-axis > threshold * rest radius; > 1
};

// Throws InvalidArgument naming the field ("split_threshold") and the value.
void validate(const ResampleParams& params);

// Tangent axes for surfels without them: an orthonormal frame of the normal, scaled by the radius
// (#P by 3 each). Deterministic.
void make_tangent_frames(const Points& normals, const Values& radii, Points& tangent_u, Points& tangent_v);

// A split of row `parent` into two children: the parent row becomes child A, child B is appended.
struct SplitPlan {
  IndexList parents;  // rows split, ascending
  SurfelArrays a;     // per parent: child A's attributes (positions, normals, radii, tangents[, colors])
  SurfelArrays b;     // per parent: child B's attributes (appended as new surfels)
};

// Plans splits among `candidates` (rows, e.g. those moved by the step). Children sit at
// p -/+ (a_e / 2) e with a_e the largest semi-axis along unit direction e (a quarter of the extent
// 2 a_e); their axis along e is halved, the other kept; normal and colour copied; radius = the
// larger remaining semi-axis. Requires tangent axes. `rest_radius`: #P.
SplitPlan plan_splits(const SurfelArrays& model, const IndexList& candidates, const Values& rest_radius,
                      const ResampleParams& params);

}  // namespace surfeledit
