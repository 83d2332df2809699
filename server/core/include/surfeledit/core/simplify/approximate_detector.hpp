// Approximate collision detection on the simplified deformable region (docs/algorithms.md §6, thesis §9.3).
//
// The deformable surfels are clustered once at reset (SimplifyParams). Each step, every cluster's
// simplified surfel is rebuilt from its members' current positions (centroid; radius covering their
// discs) and tested with the configured algorithm's inside/outside test against its reference (zero
// region for Simple/Temporal, the original model for Robust), with its own state and temporal-coherence
// sphere. The members of a cluster (original surfels, spatial coherence) are tested only when
//   - its simplified surfel collides, or
//   - its simplified surfel is closer to the zero region than member_margin x the cluster radius, or
//   - one of its members collided at the previous step (memorised until it agrees with its cluster);
// a tested member goes through exactly the exact algorithm's per-surfel update, so members still
// inside their temporal-coherence sphere are skipped. Members not tested keep "not colliding"
// (Robust: at their next test their inside state is re-derived from the last position at which they
// were tested and found not colliding, so the parity spans the untested steps).
// A one-surfel cluster is its own simplified surfel and is always tested; with cluster_size 1 (or
// method None) every member is tested every step (clusters then only hold a surfel and the surfels
// split from it), so the result equals the exact detector's, step by step. Surfels inserted later
// join their parent's cluster.
// Supported algorithms: Simple, Temporal, Robust (Improved is order-dependent and is rejected).
#pragma once

#include <memory>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/simplify/cluster_map.hpp"
#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {

// What the approximate detector did in its last step, beside CollisionStats.
struct ApproximateStats {
  Index clusters = 0;           // non-empty clusters
  Index singletons = 0;         // of which one-surfel clusters (always tested)
  Index colliding_clusters = 0; // simplified surfels reported colliding
  Index near_clusters = 0;      // clusters tested for being within the margin of the zero region
  Index active_clusters = 0;    // clusters whose members were tested
  Index cluster_queries = 0;    // nearest-neighbour queries made for simplified surfels
  double simplify_ms = 0.0;     // time of the clustering at the last reset
};

class ApproximateDetector : public CollisionDetector {
 public:
  virtual const SimplifyParams& simplify_params() const = 0;
  virtual const ClusterMap& clusters() const = 0;            // the deformable rows' clusters
  virtual const ApproximateStats& approx_stats() const = 0;  // of the last detect()

 protected:
  using CollisionDetector::CollisionDetector;
};

// An approximate detector for `params.algorithm` (nullptr for None). Validates both params; throws
// InvalidArgument naming "algorithm" for Improved.
std::unique_ptr<ApproximateDetector> make_approximate_detector(const CollisionParams& params,
                                                               const SimplifyParams& simplify);

}  // namespace surfeledit
