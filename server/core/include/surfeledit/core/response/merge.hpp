// Merge (union) of the deformed region with the zero region (§7 d of docs/algorithms.md; thesis §11.3).
//
// The colliding deformable surfels go; the zero surfels inside the deformed region go, classified by
// the nearest-surfel test (§2) against the deformed region closed up with the original deformable
// surfels, normals flipped; the kept surfels within about one radius of the intersection are the
// feature surfels, on both sides: the input of the sharp crease (crease.hpp).
// Only the zero surfels in the deformed region's bounding box (grown by the largest radius) are
// classified; a classified surfel settles every candidate in its surfel-free ball (spatial coherence,
// as §4.2), so the surfels deep inside are mostly never queried.
#pragma once

#include <vector>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct MergeParams {
  double inside_margin = 0.1;   // a zero surfel is inside when its offset (p1 - p2) . n2 <= -margin x its
                                // radius: surfels on (or within margin of) the deformed surface stay
  bool close_with_originals = true;  // thesis: close the open deformed region with the original deformable
                                     // surfels, normals flipped, before classifying the zero surfels
  double knn_eps = 1.0;         // approximate nearest deformed surfel for the zero surfels (as CollisionParams::
                                // knn_eps: at most sqrt(1 + eps) x as far as the nearest); deep surfels are
                                // slow to query exactly and any near-nearest surfel classifies them; 0 = exact
  double feature_radius_factor = 1.0;  // a kept surfel is a feature surfel when its estimated distance to the
                                       // intersection (offset to the other surface / sine of the angle of
                                       // the normals) is within this x its radius (thesis: one radius) and
                                       // a removed surfel of its own side is within twice that
};

// Throws InvalidArgument naming the field on a non-finite or negative value.
void validate(const MergeParams& params);

struct MergeStats {
  Index candidates = 0;      // zero surfels classified (those in the deformed region's bounding box)
  Index queried = 0;         // of them, classified by their own nearest-surfel queries (the rest were
                             // settled by a neighbour's surfel-free ball)
  Index removed_zero = 0;    // of them, inside the deformed region
  double merge_ms = 0.0;     // time of merge_regions
};

struct MergeResult {
  IdList removed;              // ids to remove, ascending: the colliding deformable surfels and the zero
                               // surfels inside the deformed region
  IdList features_deformable;  // kept deformable feature surfels, ascending
  IdList features_zero;        // kept zero feature surfels, ascending
  MergeStats stats;
};

// `model`: the deformed model; `regions`: #P labels of its rows (Zero = rigid); `original_positions`,
// `original_normals`: #D by 3, the deformable surfels before the deformation (any order, unit normals;
// may be empty when `params.close_with_originals` is off); `colliding`: ids of the colliding deformable
// surfels (a detector's result). Validates everything first (InvalidArgument / NotFound naming the
// field); the model is not changed. No colliding surfel: an empty result.
MergeResult merge_regions(const SurfelModel& model, const std::vector<Region>& regions,
                          const Points& original_positions, const Points& original_normals,
                          const IdList& colliding, const MergeParams& params = {});

}  // namespace surfeledit
