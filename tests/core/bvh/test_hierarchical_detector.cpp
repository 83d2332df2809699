// Collision detection behind bounding volume hierarchies (issue 4): every configuration gives the
// colliding set of the same algorithm without a hierarchy, on every step of the scripted scene (with
// insertions and removals mid-scenario); the extended variant equals Robust; a reset on two threads; a background
// rebuild while steps arrive.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <thread>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"

using namespace surfeledit;
using namespace surfeledit::testing;

namespace {

std::string describe(const CollisionParams& c, const HierarchyParams& h) {
  return std::string(to_string(c.algorithm)) + " zero=" + to_string(h.zero) + " deformable=" + to_string(h.deformable) +
         " update=" + bvh::to_string(h.tree.update) + " sat=" + bvh::to_string(h.sat) +
         " extended=" + (h.extended ? "true" : "false");
}

// Runs the scripted slab scene with `reference` (no hierarchy) and `params` + `hierarchy` side by
// side, with the splits (step 4) and removals (step 7) of run_against_oracle; returns the number of
// steps whose colliding sets differ and checks the counters.
// `bound`, when given, is the displacement bound det's detect input carries at each step (none when empty).
// `spacing`: of the scene's samples (slab_and_sphere).
using BoundFn = std::function<std::optional<double>(const TestScene&, const Points& previous)>;
int run_pair(const CollisionParams& params, const HierarchyParams& hierarchy, const CollisionParams& reference,
             Index* candidates_seen = nullptr, const BoundFn& bound = nullptr, double spacing = 0.08) {
  TestScene scene = slab_and_sphere(spacing);
  const std::vector<ScriptStep> script = slab_script();
  auto ref = CollisionDetector::create(reference);
  auto det = CollisionDetector::create(params, hierarchy);
  ref->reset(scene.view());
  det->reset(scene.view());
  int differing = 0;
  auto inserted = [&](const IndexList& parents) {
    ref->on_inserted(scene.view(), parents);
    det->on_inserted(scene.view(), parents);
  };
  auto removed = [&](const std::vector<bool>& keep) {
    ref->on_removed(keep);
    det->on_removed(keep);
  };
  play_script(scene, script, true, inserted, removed, [&](std::size_t k, const Points& previous) {
    const CollisionResult want = ref->detect(scene.view(), previous);
    CollisionScene view = scene.view();
    if (bound) view.displacement_bound = bound(scene, previous);
    const CollisionResult got = det->detect(view, previous);
    if (got.colliding != want.colliding) ++differing;
    EXPECT_EQ(got.colliding, want.colliding) << describe(params, hierarchy) << " step " << k;
    // Temporal skips the broad phase (bvh/hierarchical_detector.hpp): no overlap test.
    if (params.algorithm == CollisionAlgorithm::Temporal) EXPECT_EQ(got.stats.nv, 0) << describe(params, hierarchy);
    else EXPECT_GT(got.stats.nv, 0) << describe(params, hierarchy) << " step " << k;
    EXPECT_LE(got.stats.np, got.stats.deformable);
    if (candidates_seen) *candidates_seen += got.stats.np;
  });
  return differing;
}

std::vector<HierarchyParams> every_configuration(bool extended) {
  std::vector<HierarchyParams> out;
  for (auto zero : {ZeroHierarchy::Aabb, ZeroHierarchy::Obb, ZeroHierarchy::Sphere})
    for (auto def : {DeformableHierarchy::None, DeformableHierarchy::Aabb})
      for (auto update : {bvh::UpdateMode::BottomUp, bvh::UpdateMode::TopDown, bvh::UpdateMode::Hybrid,
                          bvh::UpdateMode::Bounded})
        for (auto sat : {bvh::SatMode::Lite, bvh::SatMode::Full}) {
          HierarchyParams h;
          h.zero = zero;
          h.deformable = def;
          h.tree.update = update;
          h.sat = sat;
          h.extended = extended;
          out.push_back(h);
        }
  return out;
}

}  // namespace

// zero kinds x deformable none/aabb x update strategies x sat lite/full, for each algorithm a
// hierarchy can serve: the same colliding set as without a hierarchy on every step.
TEST(CollisionBvh, EveryConfigurationEqualsNoHierarchyEveryStep) {
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Temporal, CollisionAlgorithm::Robust}) {
    for (const HierarchyParams& h : every_configuration(false)) {
      Index candidates = 0;
      EXPECT_EQ(run_pair(params_of(a), h, params_of(a), &candidates), 0) << describe(params_of(a), h);
      // Temporal skips the broad phase (it tests whatever leaves its sphere, a candidate or not).
      if (a != CollisionAlgorithm::Temporal) EXPECT_GT(candidates, 0) << describe(params_of(a), h);
    }
  }
}

// A displacement bound handed over in the detect input (as EditSession hands the deformation's): twice the
// largest |p - previous| of a deformable row, computed here by brute force, on every step whose radii are
// those of the step before (none after the splits and removals, as the session does). Every configuration
// still gives the colliding set of the detector without a hierarchy on every step.
TEST(CollisionBvh, HandedOverDisplacementBoundEqualsNoHierarchyEveryStep) {
  Values last_radii;
  const BoundFn bound = [&](const TestScene& scene, const Points& previous) {
    return brute_displacement_bound(scene, previous, last_radii);
  };
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Robust}) {
    for (const HierarchyParams& h : every_configuration(false)) {
      if (h.tree.update != bvh::UpdateMode::Bounded || h.sat != bvh::SatMode::Lite) continue;
      last_radii = slab_and_sphere().radii;  // run_pair's scene at the reset
      Index candidates = 0;
      EXPECT_EQ(run_pair(params_of(a), h, params_of(a), &candidates, bound), 0) << describe(params_of(a), h);
      EXPECT_GT(candidates, 0) << describe(params_of(a), h);
    }
  }
}

// A handed-over bound that is too small (0 while the sphere moves into the slab): the boxes do not grow, so
// the broad phase misses candidates and the colliding set departs from the detector without a hierarchy --
// the equality above would catch a wrong bound. A debug build refuses it outright (Internal, naming it). A
// bound that is negative or not finite is refused before anything changes.
TEST(CollisionBvh, TooSmallDisplacementBoundIsCaught) {
  for (auto def : {DeformableHierarchy::None, DeformableHierarchy::Aabb}) {
    HierarchyParams h;
    h.zero = ZeroHierarchy::Aabb;
    h.deformable = def;
    const BoundFn zero = [](const TestScene&, const Points&) -> std::optional<double> { return 0.0; };
#if defined(NDEBUG) && !defined(SURFELEDIT_CHECKED)
    ::testing::TestPartResultArray failures;
    int differing = 0;
    {
      ::testing::ScopedFakeTestPartResultReporter quiet(
          ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &failures);
      differing = run_pair(params_of(CollisionAlgorithm::Robust), h, params_of(CollisionAlgorithm::Robust), nullptr, zero);
    }
    EXPECT_GT(differing, 0) << to_string(def);
#else
    // A debug build's measured check comes first; a checked release build's is the narrow sweep's sleeping rows.
#ifdef NDEBUG
    const std::string checked = "SleepingBlocks";
#else
    const std::string checked = "displacement_bound";
#endif
    try {
      run_pair(params_of(CollisionAlgorithm::Robust), h, params_of(CollisionAlgorithm::Robust), nullptr, zero);
      ADD_FAILURE() << "a zero bound on a moving step was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::Internal);
      EXPECT_EQ(e.field(), checked) << e.what();
    }
#endif
    TestScene scene = slab_and_sphere();
    auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust), h);
    det->reset(scene.view());
    const Points previous = scene.positions;
    for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
      CollisionScene view = scene.view();
      view.displacement_bound = bad;
      try {
        det->detect(view, previous);
        ADD_FAILURE() << "bound " << bad << " accepted";
      } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
        EXPECT_EQ(e.field(), "displacement_bound") << e.what();
      }
    }
    // Unchanged by the refusals: the next step equals a fresh detector's.
    scene.move(Vec3(0, 0, -0.3), Mat3::Identity(), Vec3::Zero());
    auto fresh = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
    fresh->reset(slab_and_sphere().view());
    EXPECT_EQ(det->detect(scene.view(), previous).colliding, fresh->detect(scene.view(), previous).colliding);
  }
}

// Sphere cluster trees (issue 5) adopted as the zero hierarchy: the same colliding set as without a
// hierarchy on every step, alone and with a deformable AABB tree, at two cluster sizes.
TEST(CollisionBvh, SphereClusterTreesEqualNoHierarchyEveryStep) {
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Temporal, CollisionAlgorithm::Robust})
    for (auto zero : {ZeroHierarchy::SphereHierarchical, ZeroHierarchy::SphereIncremental})
      for (auto def : {DeformableHierarchy::None, DeformableHierarchy::Aabb})
        for (int size : {4, 18}) {
          HierarchyParams h;
          h.zero = zero;
          h.deformable = def;
          h.clusters.cluster_size = size;
          h.clusters.threads = 1;
          Index candidates = 0;
          EXPECT_EQ(run_pair(params_of(a), h, params_of(a), &candidates), 0) << describe(params_of(a), h) << " size " << size;
          if (a != CollisionAlgorithm::Temporal) EXPECT_GT(candidates, 0) << describe(params_of(a), h);
        }
}

// knn_eps = 0 set explicitly (behind an AABB zero tree, which run_pair needs) is the exact detector.
TEST(CollisionBvh, KnnEpsZeroEqualsExact) {
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Temporal, CollisionAlgorithm::Robust}) {
    CollisionParams p = params_of(a);
    p.knn_eps = 0.0;
    HierarchyParams h;
    h.zero = ZeroHierarchy::Aabb;
    EXPECT_EQ(run_pair(p, h, params_of(a)), 0) << to_string(a);
  }
}

// The extended variants (narrow phase against the original model) equal Robust without a hierarchy.
TEST(CollisionBvh, ExtendedEqualsRobustEveryStep) {
  for (const HierarchyParams& h : every_configuration(true)) {
    EXPECT_EQ(run_pair(params_of(CollisionAlgorithm::Robust), h, params_of(CollisionAlgorithm::Robust)), 0)
        << describe(params_of(CollisionAlgorithm::Robust), h);
  }
}

// A reset on two threads, on a model large enough for the narrow phase to be built beside the broad phase's trees
// (at_once.hpp: at least 16384 rows), equals Robust without a hierarchy on one thread, every step.
TEST(CollisionBvh, ResetOnTwoThreadsEqualsOneThreadWithoutAHierarchy) {
  ASSERT_GE(slab_and_sphere(0.03).rows(), 16384);
  for (auto zero : {ZeroHierarchy::Aabb, ZeroHierarchy::Obb}) {
    for (bool extended : {false, true}) {
      HierarchyParams h;
      h.zero = zero;
      h.deformable = DeformableHierarchy::Aabb;
      h.extended = extended;
      EXPECT_EQ(run_pair(params_of(CollisionAlgorithm::Robust, 2), h, params_of(CollisionAlgorithm::Robust), nullptr,
                         nullptr, 0.03),
                0)
          << describe(params_of(CollisionAlgorithm::Robust, 2), h);
    }
  }
}

// A collision somewhere the broad phase does not look: a colliding surfel deep inside the slab keeps
// its state (Robust), and a hierarchy over a far-away zero region finds no candidate at all.
TEST(CollisionBvh, NoCandidatesWhenFarFromTheZeroRegion) {
  TestScene scene = slab_and_sphere();
  HierarchyParams h;
  h.zero = ZeroHierarchy::Aabb;
  h.deformable = DeformableHierarchy::Aabb;
  auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust), h);
  det->reset(scene.view());
  const Points previous = scene.positions;
  scene.move(Vec3(0, 0, 0.01));  // up, away from the slab (gap 0.35)
  const CollisionResult r = det->detect(scene.view(), previous);
  EXPECT_EQ(r.stats.np, 0);
  EXPECT_EQ(r.stats.queries, 0);
  EXPECT_TRUE(r.colliding.empty());
  EXPECT_EQ(det->hierarchy_info().status, "refit");
}

// The concave fold of test_collision_robust: Simple behind a hierarchy sees what Simple sees (the
// zero region's own inside test), by design not more -- concave collisions are not its definition;
// the extended variant (original-model test) equals Robust there on every step.
TEST(CollisionBvh, ConcaveFoldSimpleAsWithoutExtendedAsRobust) {
  const ConcaveFold fold;
  const SampledSurfels& s = fold.s;
  const std::vector<Region>& regions = fold.regions;
  HierarchyParams tree;
  tree.zero = ZeroHierarchy::Aabb;
  tree.deformable = DeformableHierarchy::Aabb;
  HierarchyParams extended = tree;
  extended.extended = true;
  Points pos = s.positions, nrm = s.normals;
  auto simple = CollisionDetector::create(params_of(CollisionAlgorithm::Simple));
  auto simple_tree = CollisionDetector::create(params_of(CollisionAlgorithm::Simple), tree);
  auto robust = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
  auto robust_ext = CollisionDetector::create(params_of(CollisionAlgorithm::Robust), extended);
  for (auto* d : {simple.get(), simple_tree.get(), robust.get(), robust_ext.get()})
    d->reset(CollisionScene{pos, nrm, s.radii, regions});
  const int steps = fold.steps;
  std::size_t robust_max = 0;
  for (int k = 0; k < steps; ++k) {
    const Points previous = pos;
    fold.bend(pos, nrm);
    const CollisionScene view{pos, nrm, s.radii, regions};
    const IndexList a = simple->detect(view, previous).colliding, b = simple_tree->detect(view, previous).colliding;
    const IndexList c = robust->detect(view, previous).colliding, d = robust_ext->detect(view, previous).colliding;
    EXPECT_EQ(a, b) << "simple behind a hierarchy, step " << k;
    EXPECT_EQ(c, d) << "extended vs robust, step " << k;
    robust_max = std::max(robust_max, c.size());
  }
  EXPECT_GT(robust_max, 50u);  // the fold does collide
}

// Rebuild on idle: a background rebuild while steps keep arriving. Every step still equals the
// detector without a hierarchy (no step sees a half-built tree: it keeps the refit one until the new
// one is complete), the finished tree is swapped in at a step boundary, and a rebuild started before
// rows were removed is dropped. Run under ThreadSanitizer in the SURFELEDIT_TSAN build.
TEST(CollisionBvh, BackgroundRebuildWhileStepsArrive) {
  TestScene scene = slab_and_sphere(0.04);
  HierarchyParams h;
  h.zero = ZeroHierarchy::Aabb;
  h.deformable = DeformableHierarchy::Aabb;
  auto ref = CollisionDetector::create(params_of(CollisionAlgorithm::Robust));
  auto det = CollisionDetector::create(params_of(CollisionAlgorithm::Robust), h);
  ref->reset(scene.view());
  det->reset(scene.view());
  EXPECT_EQ(det->hierarchy_info().status, "fresh");
  auto step = [&](const Vec3& t) {
    const Points previous = scene.positions;
    scene.move(t);
    const auto t0 = std::chrono::steady_clock::now();
    const CollisionResult got = det->detect(scene.view(), previous);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(got.colliding, ref->detect(scene.view(), previous).colliding);
    return ms;
  };
  for (int k = 0; k < 6; ++k) step(Vec3(0, 0, -0.06));
  EXPECT_EQ(det->hierarchy_info().status, "refit");
  ASSERT_TRUE(det->start_rebuild(scene.view()));
  EXPECT_FALSE(det->start_rebuild(scene.view()));  // one at a time
  int steps = 0;
  while (det->hierarchy_info().rebuilds_adopted == 0 && steps < 2000) {
    step(Vec3(0, 0, steps % 2 ? 0.002 : -0.002));
    ++steps;
  }
  EXPECT_EQ(det->hierarchy_info().rebuilds_adopted, 1);
  EXPECT_GT(det->hierarchy_info().last_rebuild_ms, 0.0);
  for (int k = 0; k < 4; ++k) step(Vec3(0, 0, -0.05));
  // Rows removed while a rebuild runs: its tree no longer matches and is dropped.
  ASSERT_TRUE(det->start_rebuild(scene.view()));
  std::vector<bool> keep(scene.rows(), true);
  for (Index r = 0, j = 0; r < scene.rows(); ++r)
    if (scene.regions[r] != Region::Zero && j++ % 13 == 0) keep[r] = false;
  scene.remove(keep);
  ref->on_removed(keep);
  det->on_removed(keep);
  const double before = det->hierarchy_info().last_rebuild_ms;
  for (int k = 0; k < 2000 && det->hierarchy_info().last_rebuild_ms == before; ++k) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
    step(Vec3(0, 0, k % 2 ? 0.002 : -0.002));
  }
  EXPECT_EQ(det->hierarchy_info().rebuilds_adopted, 1);
  for (int k = 0; k < 3; ++k) step(Vec3(0, 0, 0.05));
}

// Robust with the winding number behind a hierarchy (docs/algorithms.md §4.6): an open box (the zero region: bottom
// and sides, 2 x 2 x 2) whose lid (the deformable part) is pushed into it. Points crossing the opening's middle change
// their inside state farther than their step from every zero surfel; the opening's ball makes them candidates, so
// each hierarchy reports what the detector without one does, step by step. (Before it, 84 of the 655 colliding lid
// points were missing behind an AABB tree.)
TEST(HierarchicalDetector, RowsCrossingTheOpenBoundaryAreCandidates) {
  TestScene scene;
  std::vector<Vec3> p, n;
  const int cells = 40;  // spacing 0.05
  auto at = [&](int i) { return -1.0 + 2.0 * i / cells; };
  for (int i = 0; i <= cells; ++i)
    for (int j = 0; j <= cells; ++j) {
      p.emplace_back(at(i), at(j), -1.0), n.emplace_back(0, 0, -1);
      p.emplace_back(at(i), at(j), 1.0), n.emplace_back(0, 0, 1);
    }
  for (int i = 0; i <= cells; ++i)
    for (int j = 1; j < cells; ++j) {
      p.emplace_back(1.0, at(i), at(j)), n.emplace_back(1, 0, 0);
      p.emplace_back(-1.0, at(i), at(j)), n.emplace_back(-1, 0, 0);
      p.emplace_back(at(i), 1.0, at(j)), n.emplace_back(0, 1, 0);
      p.emplace_back(at(i), -1.0, at(j)), n.emplace_back(0, -1, 0);
    }
  const Index rows = static_cast<Index>(p.size());
  scene.positions.resize(rows, 3);
  scene.normals.resize(rows, 3);
  scene.radii = Values::Constant(rows, 0.04);
  for (Index r = 0; r < rows; ++r) {
    scene.positions.row(r) = p[r].transpose();
    scene.normals.row(r) = n[r].transpose();
    const bool lid = p[r].z() > 0.99 && std::abs(p[r].x()) < 0.99 && std::abs(p[r].y()) < 0.99;
    scene.regions.push_back(lid ? Region::One : Region::Zero);
  }
  CollisionParams params = params_of(CollisionAlgorithm::Robust);
  params.inside = InsideMode::Winding;
  HierarchyParams aabb, obb_bounded;
  aabb.zero = ZeroHierarchy::Aabb;
  obb_bounded.zero = ZeroHierarchy::Obb;
  obb_bounded.deformable = DeformableHierarchy::Aabb;
  auto plain = CollisionDetector::create(params);
  auto with_aabb = CollisionDetector::create(params, aabb);
  auto with_obb = CollisionDetector::create(params, obb_bounded);
  for (auto* d : {plain.get(), with_aabb.get(), with_obb.get()}) d->reset(scene.view());
  std::size_t far = 0;  // reported lid points farther than their step and both radii from every zero surfel
  for (int k = 0; k < 8; ++k) {
    const Points previous = scene.positions;
    scene.move(Vec3(0, 0, -0.1));
    const IndexList got = plain->detect(scene.view(), previous).colliding;
    EXPECT_EQ(with_aabb->detect(scene.view(), previous).colliding, got) << "step " << k;
    EXPECT_EQ(with_obb->detect(scene.view(), previous).colliding, got) << "step " << k;
    if (k + 1 < 8) continue;
    for (Index r : got) {
      double d2 = std::numeric_limits<double>::infinity();
      for (Index z = 0; z < rows; ++z)
        if (scene.regions[z] == Region::Zero) d2 = std::min(d2, (scene.positions.row(z) - scene.positions.row(r)).squaredNorm());
      far += std::sqrt(d2) > 0.04 + 0.1 + 0.04;
    }
  }
  EXPECT_GT(far, 50u);  // not vacuous: the zero tree's broad phase alone would not have tested them
}
