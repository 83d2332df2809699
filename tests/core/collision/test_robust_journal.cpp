// Robust's undo journal holds the rows a step tested and no others (robust_kernel.hpp, State: the old position
// of a point that does not collide is implicit, so a point that stays inside its sphere keeps its state's
// bytes). A patch of deformable surfels sinks through a rigid plane, then drags along it, step by step: every
// step's result must equal the brute-force oracle's, and the journal's image may hold at most the rows the step
// re-evaluated with a query (journal_tested) plus those that started or stopped colliding. The steps where few
// rows are tested are the point: before, every moved row's state changed (its last free position), so every
// step's journal held all of them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <string>
#include <vector>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"
#include "surfeledit/core/hierarchy.hpp"

namespace surfeledit {
namespace {

using namespace testing;

// A rigid plane z = 0 (side x side surfels 0.1 apart, normals +z) and a deformable patch (patch x patch
// surfels 0.1 apart) at height `height` above its middle.
TestScene plane_and_patch(int side, int patch, double height) {
  TestScene s;
  const Index n = side * side + patch * patch;
  s.positions.resize(n, 3);
  s.normals.resize(n, 3);
  s.radii.resize(n);
  Index r = 0;
  auto add = [&](double x, double y, double z, Region region) {
    s.positions.row(r) << x, y, z;
    s.normals.row(r) << 0.0, 0.0, 1.0;
    s.radii[r] = 0.06;
    s.regions.push_back(region);
    ++r;
  };
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) add(0.1 * (i - side / 2), 0.1 * (j - side / 2), 0.0, Region::Zero);
  for (int i = 0; i < patch; ++i)
    for (int j = 0; j < patch; ++j) add(0.1 * (i - patch / 2) + 0.03, 0.1 * (j - patch / 2) + 0.04, height, Region::One);
  return s;
}

// Rows a journal's image holds: its bytes against images of a known number of rows (save_image of 0 and 1 row).
Index journal_rows(const CollisionDetector& det, const DetectorImage& image, Index some_row) {
  const IndexList none, one{some_row};
  const std::size_t base = det.save_image(&none)->bytes();
  const std::size_t per_row = det.save_image(&one)->bytes() - base;
  EXPECT_EQ((image.bytes() - base) % per_row, 0u);
  return static_cast<Index>((image.bytes() - base) / per_row);
}

TEST(RobustJournal, AStepHoldsOnlyTheRowsItTestedOrWhoseCollisionChanged) {
  TestScene scene = plane_and_patch(31, 12, 0.5);
  const Index first_deformable = 31 * 31;
  const CollisionParams p = params_of(CollisionAlgorithm::Robust);
  auto det = CollisionDetector::create(p);
  det->reset(scene.view());
  Oracle oracle(p);
  oracle.reset(scene);
  IndexList colliding;
  int checked = 0, sparse = 0, collided = 0;
  for (int k = 0; k < 60; ++k) {
    // 25 steps down through the plane (0.03 each), then along it.
    const Vec3 t = k < 25 ? Vec3(0.0, 0.0, -0.03) : Vec3(0.013, 0.007, 0.0);
    const Points previous = scene.positions;
    scene.move(t);
    const bool saving = det->start_journal();
    const CollisionResult got = det->detect(scene.view(), previous);
    std::vector<double> depths;
    const IndexList want = oracle.detect(scene, previous, &depths);
    ASSERT_EQ(got.colliding, want) << "step " << k;
    ASSERT_EQ(got.depths, depths) << "step " << k;
    if (saving) {
      std::vector<std::uint8_t> tested(static_cast<std::size_t>(scene.rows()), 0);
      ASSERT_TRUE(det->journal_tested(tested));
      Index bound = 0;
      for (std::uint8_t f : tested) bound += f;
      IndexList changed;  // rows that started or stopped colliding
      std::set_symmetric_difference(colliding.begin(), colliding.end(), got.colliding.begin(), got.colliding.end(),
                                    std::back_inserter(changed));
      for (Index r : changed) bound += tested[static_cast<std::size_t>(r)] ? 0 : 1;
      const auto image = det->journal_image();
      ASSERT_NE(image, nullptr);
      const Index held = journal_rows(*det, *image, first_deformable);
      EXPECT_LE(held, bound) << "step " << k;
      ++checked;
      sparse += 2 * bound < 12 * 12;
    }
    det->stop_journal();
    collided += !got.colliding.empty();
    colliding = got.colliding;
  }
  EXPECT_GT(collided, 10);  // the patch went through the plane and stayed in it
  EXPECT_GT(checked, 30);
  EXPECT_GT(sparse, 10);    // steps that tested fewer than half of the rows: the ones the bound is about
}

// restore_journal() must put back every byte a step changed, for every row the sweeps visit (candidates of a broad
// phase or not). Truth: a twin detector that never takes a step back. Before each of its steps, one detector takes
// another step (larger and sideways, so rows leave spheres the real step keeps) and takes it back through the
// journal; then both take the real step. Their results and their work (rows re-tested, queries: an emptied sphere
// or a forgotten inside state left behind shows there, if not at once then once its row nears the plane) must be
// equal at every step. With and without trees; on one thread, and on two with the sweep parallel at every size
// (its chunks' journal parts; a checked build's throw inside the parallel region fails the test, not the run).
TEST(RobustJournal, AStepTakenBackLeavesNoTrace) {
  std::vector<HierarchyParams> hierarchies(3);
  hierarchies[1].zero = ZeroHierarchy::Aabb;
  hierarchies[2].zero = ZeroHierarchy::Obb;
  hierarchies[2].deformable = DeformableHierarchy::Aabb;
  for (int threads : {1, 2}) {
    for (std::size_t h = 0; h < hierarchies.size(); ++h) {
      SCOPED_TRACE("hierarchy " + std::to_string(h) + ", threads " + std::to_string(threads));
      TestScene scene = plane_and_patch(31, 12, 1.2);
      const CollisionParams p = params_of(CollisionAlgorithm::Robust, threads);
      auto det = CollisionDetector::create(p, hierarchies[h]);
      det->reset(scene.view());
      auto twin = det->clone();
      ASSERT_NE(twin, nullptr);
      int collided = 0;
      for (int k = 0; k < 50; ++k) {
        // Down through the plane in steps of 0.05 with a sideways wobble, then up and away from it in steps of 0.1:
        // rows tested near the plane (small spheres) leave them once they are outside the broad phase.
        const Vec3 t = k < 32 ? Vec3(0.02 * ((k % 3) - 1), 0.015 * ((k % 2) ? 1 : -1), -0.05) : Vec3(0.03, 0.0, 0.1);
        const Points previous = scene.positions;
        TestScene other = scene;
        other.move(t + Vec3(0.09, -0.05, 0.04 * ((k % 2) ? 1 : -1)));
        // After a journal that held most rows the next ones keep no states (RowDetector::start_journal); those are
        // started and stopped until one does, so that every step is taken back through a journal.
        bool saving = false;
        for (int tries = 0; tries < 10 && !(saving = det->start_journal()); ++tries) det->stop_journal();
        ASSERT_TRUE(saving) << "step " << k;
        det->detect(other.view(), previous);
        det->restore_journal();
        det->stop_journal();
        scene.move(t);
        const CollisionResult a = det->detect(scene.view(), previous);
        testing::expect_same_detection(a, twin->detect(scene.view(), previous), "step " + std::to_string(k), false);
        if (HasFailure()) return;
        collided += !a.colliding.empty();
      }
      EXPECT_GT(collided, 5);
    }
  }
}

}  // namespace
}  // namespace surfeledit
