// Sharp crease at the intersection of two merged regions (§7 d of docs/algorithms.md; thesis §11.3).
//
// Each feature surfel i of one side pairs with its nearest feature surfel j of the other side; both
// tangent planes and the plane through their midpoint orthogonal to both (normal n_i x n_j) meet in
// one point x of the intersection curve. i moves to x (normal kept) and its disc is clipped at the
// curve: the clip line through x along n_i x n_j, keeping the half that points away from the other
// surface. Where i moved more than gap_factor x its radius, a copy covers the uncovered part of the
// old disc (Eq. 11.1): along the tangent axis u on which the move projects most (|d_u|), the copy spans
// from the old disc's far edge to the curve: centre p - sign(d_u) (|u| - |d_u|) / 2 u/|u|, axis
// u (|u| + |d_u|) / (2 |u|), v unchanged (circular discs: u is the move's tangential direction, and the
// copy's radius is (r + |d_u|) / 2).
#pragma once

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct CreaseParams {
  double gap_factor = 0.75;      // a surfel moved more than this x its radius gets a gap-covering copy
  double max_move_factor = 1.0;  // a surfel whose curve point is farther than this x its radius stays put
                                 // (a tangent plane is off its surface by ~ curvature x move^2 / 2)
  double min_angle = 0.1;        // radians: pairs whose normals are closer than this (near-parallel
                                 // planes, no crease) stay put
};

// Throws InvalidArgument naming the field on a non-finite or non-positive value.
void validate(const CreaseParams& params);

struct CreaseResult {
  IdList moved;            // ids of the surfels moved onto the curve, ascending
  Points positions;        // #moved by 3: their new positions (points of the intersection curve)
  Points clip_points;      // #moved by 3: clip line points (= positions)
  Points clip_dirs;        // #moved by 3: unit clip line directions; the kept half is where
                           // (y - clip_point) . (normal x clip_dir) >= 0 (as SurfelModel's clip lines)
  SurfelArrays inserted;   // gap-covering copies (Eq. 11.1): normals, radii, colors of the parent; tangents
                           // when the model has them; unclipped (no clip arrays)
  IdList inserted_parents; // #inserted: id of the surfel each copy was made from
};

// `features_a`, `features_b`: ids of the feature surfels of the two sides (merge_regions's
// features_deformable and features_zero), kept rows of `model`. Validates first (NotFound / InvalidArgument
// naming the field); the model is not changed (apply with the SurfelModel setters).
CreaseResult crease(const SurfelModel& model, const IdList& features_a, const IdList& features_b,
                    const CreaseParams& params = {});

// Applies `crease` to `model` (before or after removing MergeResult::removed: it touches kept surfels
// only): moves the surfels, sets their clip lines, appends the copies (unclipped). Returns the copies'
// ids, in the order of crease.inserted. Validates first (the model is unchanged on a throw).
IdList apply_crease(SurfelModel& model, const CreaseResult& crease);

// The point where the tangent planes (p_i, n_i), (p_j, n_j) and the plane through their midpoint
// orthogonal to both meet; false (x untouched) when the normals are parallel within `min_angle`.
bool crease_point(const Vec3& p_i, const Vec3& n_i, const Vec3& p_j, const Vec3& n_j, double min_angle,
                  Vec3& x);

}  // namespace surfeledit
