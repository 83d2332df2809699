// A collision detector in a snapshot (docs/journal.md "Snapshots"): its params, then its own state
// (CollisionDetector::save_state). Only detectors that say snapshottable() can be written: the row
// detectors Simple, Temporal and Robust (inside test "nearest", no swept test) without a hierarchy or
// clusters; every other kind (hierarchies, approximate detection on clusters, Improved, inside modes
// winding and vote, the swept test) makes its session not snapshottable.
#pragma once

#include <memory>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit {

void save_params(SnapshotWriter& out, const CollisionParams& params);
// Validated (InvalidArgument "snapshot" naming the field).
CollisionParams load_params(SnapshotReader& in);

// Internal when !detector.snapshottable().
void save_detector(SnapshotWriter& out, const CollisionDetector& detector);
// A detector equal to the one saved (its every later result the same).
std::unique_ptr<CollisionDetector> load_detector(SnapshotReader& in);

}  // namespace surfeledit
