// Intersection curves from the crease points (§7 d of docs/algorithms.md; thesis §11.3, Eq. 11.2).
//
// Points closer than merge_factor x radius are one point. A curve starts at an unused point and its
// nearest neighbour; from its last vertex v (previous edge e1 = (u, v)) it goes on to the nearest of v's
// n nearest unused points w whose edge makes an angle larger than min_angle with e1 (the angle u-v-w;
// thesis: pi/2) and is at most max_edge_factor x radius long, until it comes back to its first point
// (closed) or finds none (then it is extended the same way from its first point). Unused points start
// further curves. Then an edge whose end bends more than refine_angle is split by the 4-point rule
//   p_new = -w p_{i-1} + (1/2 + w) p_i + (1/2 + w) p_{i+1} - w p_{i+2}   (w = 1/16),
// the ends of an open curve mirrored (p_{-1} = 2 p_0 - p_1).
#pragma once

#include <vector>

#include "surfeledit/core/types.hpp"

namespace surfeledit {

struct CurveParams {
  double refine_angle = 0.5;      // radians: an edge whose end vertex bends more than this is split
  double weight = 1.0 / 16.0;     // w of the 4-point rule; smooth for 0 < w < (sqrt(5) - 1) / 8
  int refine_passes = 2;          // subdivision passes at most (each splits every edge that bends too much)
  double min_angle = 1.5707963267948966;  // radians: the angle u-v-w of consecutive edges must exceed this
  int neighbours = 10;            // n: nearest points looked at from each vertex
  double merge_factor = 0.5;      // points closer than this x radius are merged into one
  double max_edge_factor = 3.0;   // an edge is at most this x radius long (else the curve ends there)
  std::size_t min_points = 3;     // curves with fewer points are dropped (stray pairs)
};

// Throws InvalidArgument naming the field on a non-finite / out-of-range value.
void validate(const CurveParams& params);

struct Curve {
  Points points;        // #K by 3, in curve order
  bool closed = false;  // the last point connects back to the first
};

// `positions`: #K by 3 points on the intersection (crease's positions); `radii`: #K radii of their
// surfels (the scale of merge_factor / max_edge_factor). Several disjoint curves come back as several.
std::vector<Curve> intersection_curves(const Points& positions, const Values& radii,
                                       const CurveParams& params = {});

// One step of the 4-point rule (Eq. 11.2): the point between b and c.
Vec3 four_point(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double w = 1.0 / 16.0);

// Splits every edge of `curve` whose end bends more than `refine_angle` (one pass); returns the
// number of points inserted.
Index refine_curve(Curve& curve, double refine_angle, double w = 1.0 / 16.0);

}  // namespace surfeledit
