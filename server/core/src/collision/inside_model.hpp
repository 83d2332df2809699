// The rigid solid as Temporal and Robust see it with `inside` = winding | vote (§4.6 of
// docs/algorithms.md), and the swept test of `swept` (§4.7). Built once per reset from the zero
// region (immutable, shared by detector copies):
//
// - inside(p): the nearest zero surfel k decides when p lies within k's radius of it (its tangent
//   plane, (p - p_k) . n_k < W); farther away the winding number of the zero region (> 1/2) or the
//   k-nearest vote decides. `nearest` mode keeps only the plane test (no boundary heuristic).
// - The zero region is open where the deformable part is attached. A planar hole needs no patch: its
//   cap's solid angle is at most 2 pi from any point, so w > 1/2 is still exact (§4.6). But the
//   inside state can change across the cap, far from every zero surfel, so the spheres of Temporal
//   and Robust must not reach the cap: the open boundary's loops (zero surfels whose neighbours leave
//   a wide angular gap) are wrapped in balls and clearance() keeps spheres out of them.
// - crossed(a, b): sphere-traces the segment a -> b and says whether some point of it is inside.
#pragma once

#include <memory>
#include <vector>

#include "../collision_detail.hpp"
#include "surfeledit/core/winding.hpp"

namespace surfeledit::detail {

// Throws InvalidArgument naming the field for a bad inside / winding_beta / vote_k / swept setting.
void validate_inside(const CollisionParams& params);

class InsideModel {
 public:
  // What one query found.
  struct Probe {
    Index nearest = -1;    // zero surfel nearest to p (index into the copies)
    double dist2 = 0.0;    // squared distance to it
    bool inside = false;   // p inside the rigid solid
  };

  // From the zero surfels (#Z rows each; `tree` over `positions`, shared). Throws InvalidArgument
  // when there are none.
  InsideModel(const Points& positions, const Points& normals, const Values& radii,
              std::shared_ptr<const KdTree> tree, const CollisionParams& params);

  Probe probe(const Vec3& p) const;
  // Squared radius of a sphere at p (nearest zero surfel at dist2 with radius r) that holds no zero
  // surfel and stays out of the open boundary's balls.
  double sphere_rho2(const Vec3& p, double dist2, double radius, double margin) const;
  // True when the segment a -> b enters the solid: a point of it, b included, is inside after an outside
  // one (a point that starts inside and leaves was reported when it got there; it is not crossing).
  // `probes` counts the queries made.
  bool crossed(const Vec3& a, const Vec3& b, Index& probes) const;
  // Whether crossed() is worth calling for a step t = b - a of a point now at distance sqrt(dist2)
  // from zero surfel of radius r: a wall of at least two radii can only be passed when |t| > r.
  static bool may_cross(const Vec3& t, double radius) { return t.squaredNorm() > radius * radius; }

  double radius(Index k) const { return radii_[k]; }
  std::size_t memory_bytes() const;
  std::size_t holes() const { return holes_.size(); }
  const std::vector<ZeroBall>& hole_balls() const { return holes_; }

 private:
  bool classify(const Vec3& p, Index k, double dist2) const;
  bool vote(const Vec3& p) const;
  double clearance(const Vec3& p) const;  // distance to the nearest open-boundary ball (inf: none)
  void find_holes();

  using Ball = ZeroBall;

  CollisionParams params_;
  Points positions_;  // #Z by 3
  Points normals_;    // #Z by 3
  Values radii_;      // #Z
  std::shared_ptr<const KdTree> tree_;
  std::unique_ptr<WindingNumber> winding_;  // winding mode only
  std::vector<Ball> holes_;                 // open-boundary loops
};

}  // namespace surfeledit::detail
