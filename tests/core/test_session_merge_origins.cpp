// The merge origins (MergeMemo): a Robust tool reads them from its detector's original model instead of a
// copy of its own (issue 14, memory). Each merge is checked against merge_regions called directly with the
// deformable surfels as they were when the regions were set, gathered by the test at that moment: after the
// history bound dropped the set_regions entry, after the tool's detector was re-initialised under another
// tool's moves (the origins must stay those of the regions, not of the re-initialisation), after a snapshot
// round trip, and for Simple (which keeps its own copy).
#include <gtest/gtest.h>

#include <set>

#include "session_fixture.hpp"
#include "surfeledit/core/response/merge.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "surfeledit/core/two_arms.hpp"

namespace surfeledit {
namespace {

// What merge_regions needs besides the model, gathered independently of the session.
struct Origins {
  std::vector<Region> regions;  // #P: Zero for the rigid rows, One for the deformable ones
  Points positions, normals;    // the deformable rows now, ascending rows
};

// The deformable surfels (`deformable` ids) of `model` as they are now.
Origins gather_origins(const SurfelModel& model, const IdList& deformable) {
  Origins o;
  o.regions.assign(static_cast<std::size_t>(model.size()), Region::Zero);
  std::set<Index> rows;
  for (SurfelId id : deformable) rows.insert(model.row_of(id));
  o.positions.resize(static_cast<Eigen::Index>(rows.size()), 3);
  o.normals.resize(static_cast<Eigen::Index>(rows.size()), 3);
  Eigen::Index k = 0;
  for (Index r : rows) {
    o.regions[static_cast<std::size_t>(r)] = Region::One;
    o.positions.row(k) = model.positions().row(r);
    o.normals.row(k++) = model.normals().row(r);
  }
  return o;
}

// The merge `tool` of `s` makes (no crease) against merge_regions on the same model and colliding set with
// the origins `o`; returns the removed ids (so the caller can check that the case is not vacuous).
IdList expect_merge_as_direct(EditSession& s, const Origins& o, const std::string& tool) {
  const IdList colliding = s.colliding(tool);
  EXPECT_FALSE(colliding.empty());
  const MergeResult want = merge_regions(s.model(), o.regions, o.positions, o.normals, colliding);
  const MergeOutcome got = s.merge(false, tool);
  EXPECT_EQ(got.removed, want.removed);
  IdList features;
  std::set_union(want.features_deformable.begin(), want.features_deformable.end(), want.features_zero.begin(),
                 want.features_zero.end(), std::back_inserter(features));
  EXPECT_EQ(got.features, features);
  return got.removed;
}

DeformParams sink(double dz) {
  DeformParams p;
  p.translation = Vec3(0, 0, -dz);
  return p;
}

// The sphere pushed into the slab (the 4th step collides), Robust, with a history bound of `history_mb`.
struct PushedRobust : SessionFixture {
  Origins origins;
  explicit PushedRobust(double history_mb) {
    session.configure({{"algorithm", std::string("robust")}, {"history_mb", history_mb}});
    session.set_regions({zero, {}}, {one, {}});
    origins = gather_origins(session.model(), one);
    for (int k = 0; k < 5; ++k) session.deform(sink(0.1));
  }
};

TEST(MergeOrigins, RobustHoldsNoCopyAndMergesAsTheRegionsWereSetAfterTheBoundDroppedThem) {
  PushedRobust kept(256.0), dropped(0.0);
  EXPECT_EQ(dropped.session.history().size(), 0u);  // nothing kept: not the set_regions entry either
  bool listed = false;
  for (const auto& s : kept.session.report().structures) listed |= s.name == "merge_origins";
  EXPECT_FALSE(listed) << "Robust keeps the origins in its original model";
  const IdList a = expect_merge_as_direct(kept.session, kept.origins, "");
  const IdList b = expect_merge_as_direct(dropped.session, dropped.origins, "");
  EXPECT_GT(a.size(), 10u);
  EXPECT_EQ(a, b);
  expect_same(Snapshot(kept.session), Snapshot(dropped.session), "merged with and without the history");
}

TEST(MergeOrigins, SimpleKeepsItsOwnCopy) {
  SessionFixture f;
  f.session.configure({{"algorithm", std::string("simple")}});
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  const Origins o = gather_origins(f.session.model(), f.one);
  std::size_t bytes = 0;
  for (const auto& s : f.session.report().structures)
    if (s.name == "merge_origins") bytes = s.bytes;
  EXPECT_EQ(bytes, static_cast<std::size_t>(o.positions.size() + o.normals.size()) * sizeof(double));
  for (int k = 0; k < 5; ++k) f.session.deform(sink(0.1));
  EXPECT_GT(expect_merge_as_direct(f.session, o, "").size(), 10u);
}

TEST(MergeOrigins, ASnapshotRoundTripMergesTheSame) {
  PushedRobust f(256.0);
  SnapshotWriter w;
  f.session.save(w);
  EditSession copy{"copy"};
  SnapshotReader r(w.bytes());
  copy.restore(r);
  const IdList a = expect_merge_as_direct(copy, f.origins, "");
  EXPECT_GT(a.size(), 10u);
  expect_merge_as_direct(f.session, f.origins, "");
  expect_same(Snapshot(copy), Snapshot(f.session), "merged after the snapshot");
}

// Arm a's detector is re-initialised from the model at its next step whenever arm b moved (the session does
// not follow rigid moves incrementally here): its original model is then the moved arm, while the merge must
// still close the deformed region with the arm as it was when a's regions were set.
TEST(MergeOrigins, AReinitialisedDetectorKeepsTheOriginsOfTheRegions) {
  TwoArms scene{SampleParams{0.02, 7, 0.25}};
  SessionParams params;
  params.threads = 2;
  params.incremental_rigid = false;
  EditSession s("arms", params);
  s.load(scene.model());
  for (const char* tool : {"a", "b"}) s.configure({{"algorithm", std::string("robust")}}, tool);
  s.set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
  s.set_regions({TwoArms::join(scene.body, scene.a), {}}, {scene.b, {}}, "b");
  const Origins o = gather_origins(s.model(), scene.a);
  DeformParams to_b, to_a;
  to_b.translation = Vec3(0.05, 0, 0);
  to_a.translation = Vec3(-0.04, 0, 0);
  for (int k = 0; k < 8; ++k) {
    s.deform(to_a, "b");
    s.deform(to_b, "a");  // re-initialised first: b moved
  }
  s.release("b");  // its arm may be merged into now
  EXPECT_GT(expect_merge_as_direct(s, o, "a").size(), 5u);
}

}  // namespace
}  // namespace surfeledit
