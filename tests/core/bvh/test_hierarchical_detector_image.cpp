// The hierarchical detector's journal images (hierarchical_detector_image.cpp): with a bounded deformable tree a
// step's image holds the nodes the step changed (bvh.hpp, step journal) and no copy of the tree. Truth: a clone
// taken before the journal started (a deep copy: trees, states and counters). After restore_image() of the
// journal's image the detector and the clone take the same next steps with the same colliding rows, depths and
// work (tested points, queries, overlap tests, candidates, box updates), bit for bit -- also when a back-off took
// the step back within the journal, when a background rebuild was adopted during it, and when radii changed.
#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"

using namespace surfeledit;
using namespace surfeledit::testing;

namespace {

enum class JournalCase { Steps, BackOff, Rebuild, Radii };

std::string case_name(JournalCase c) {
  switch (c) {
    case JournalCase::Steps: return "steps";
    case JournalCase::BackOff: return "back-off";
    case JournalCase::Rebuild: return "rebuild adopted";
    case JournalCase::Radii: return "radii grown";
  }
  return "?";
}

// One step of `det`: the deformable rows move by t (with the displacement bound the deformation step hands
// over, unless radii changed).
CollisionResult image_step(CollisionDetector& det, TestScene& scene, const Vec3& t, bool bound = true) {
  const Points previous = scene.positions;
  scene.move(t);
  CollisionScene view = scene.view();
  if (bound) view.displacement_bound = t.norm() * (1.0 + 1e-9);
  return det.detect(view, previous);
}

TEST(HierarchicalImage, JournalImageOfABoundedTreeRestoresWhatACloneHolds) {
  for (JournalCase c : {JournalCase::Steps, JournalCase::BackOff, JournalCase::Rebuild, JournalCase::Radii}) {
    SCOPED_TRACE(case_name(c));
    TestScene scene = slab_and_sphere(0.05);
    HierarchyParams h;
    h.zero = ZeroHierarchy::Aabb;
    h.deformable = DeformableHierarchy::Aabb;
    h.tree.update = bvh::UpdateMode::Bounded;
    auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust), h);
    det->reset(scene.view());
    for (int k = 0; k < 5; ++k) image_step(*det, scene, Vec3(0, 0, -0.06));
    const std::unique_ptr<CollisionDetector> twin = det->clone();
    ASSERT_TRUE(twin);
    const TestScene start = scene;
    const Index adopted = det->hierarchy_info().rebuilds_adopted;
    // Radii case: some deformable radii grow by 30 % (the steps then come without a displacement bound).
    auto grow = [](TestScene& t) {
      for (Index r = 0; r < t.rows(); ++r)
        if (t.regions[r] != Region::Zero && r % 7 == 0) t.radii[r] *= 1.3;
    };
    const bool bound = c != JournalCase::Radii;
    ASSERT_TRUE(det->start_journal());
    if (!bound) grow(scene);
    image_step(*det, scene, Vec3(0.01, 0, -0.04), bound);
    if (c == JournalCase::Rebuild) {  // finished before the journal's next step, which adopts it
      ASSERT_TRUE(det->start_rebuild(scene.view()));
      for (int w = 0; w < 5000 && det->hierarchy_info().status == "rebuilding"; ++w)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      ASSERT_NE(det->hierarchy_info().status, "rebuilding");
    }
    if (c == JournalCase::BackOff) {
      det->restore_journal();  // a back-off: the step taken back, then a shorter one
      scene = start;
      image_step(*det, scene, Vec3(0.005, 0, -0.02), bound);
    }
    image_step(*det, scene, Vec3(0, 0.002, -0.001), bound);
    if (c == JournalCase::Rebuild) EXPECT_EQ(det->hierarchy_info().rebuilds_adopted, adopted + 1);
    const std::shared_ptr<const DetectorImage> image = det->journal_image();
    ASSERT_TRUE(image);
    det->stop_journal();
    det->restore_image(*image);
    scene = start;
    TestScene twin_scene = start;
    if (!bound) {  // the same radii grow again: the shift must count the growth from the start's radii
      grow(scene);
      grow(twin_scene);
    }
    for (int k = 0; k < 5; ++k) {
      const Vec3 t(0.003 * (k % 2), 0, k < 3 ? -0.03 : 0.02);
      expect_same_detection(image_step(*det, scene, t, bound), image_step(*twin, twin_scene, t, bound),
                  "step " + std::to_string(k));
    }
  }
}

}  // namespace
