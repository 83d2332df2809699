// Approximate collision detection on the simplified deformable region (thesis §9.3): with cluster size
// 1 it equals the exact detector of the same algorithm at every step of a scripted scene (a sphere
// pushed through a slab, turned, pulled back), also across insertion and removal and with threads;
// at larger cluster sizes its precision and recall against the exact detector are measured, printed
// and asserted (the figures are recorded in bench/RESULTS.md): with the member margin the results equal the
// exact detector's at every step, and without it there is no false positive.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "collision_oracle.hpp"
#include "collision_scripts.hpp"
#include "surfeledit/core/settings.hpp"
#include "surfeledit/core/simplify/approximate_detector.hpp"

namespace surfeledit {
namespace {

using testing::slab_and_sphere;
using testing::slab_script;
using testing::TestScene;

// Counts of the approximate result against the exact one, summed over the steps.
struct Agreement {
  std::size_t tp = 0, fp = 0, fn = 0;
  double worst_precision = 1.0, worst_recall = 1.0;
  std::size_t member_tests = 0, exact_tests = 0;  // original surfels (re)evaluated, summed
  std::size_t queries = 0, exact_queries = 0;     // nearest-neighbour queries (approx: clusters' included)
  double precision() const { return tp + fp ? double(tp) / double(tp + fp) : 1.0; }
  double recall() const { return tp + fn ? double(tp) / double(tp + fn) : 1.0; }
};

// What run_side_by_side demands of the approximate detector at every step.
enum class Expect {
  Counts,              // nothing: precision and recall are counted
  SameResults,         // the exact detector's colliding rows and depths
  SameResultsAndTests  // those, and as many surfels tested (nothing skipped)
};

// Runs both detectors side by side on the script.
Agreement run_side_by_side(TestScene scene, const CollisionParams& cp, const SimplifyParams& sp, bool edits,
                           Expect expect) {
  auto exact = CollisionDetector::create(cp);
  auto approx = make_approximate_detector(cp, sp);
  exact->reset(scene.view());
  approx->reset(scene.view());
  approx->clusters().check();
  Agreement a;
  auto inserted = [&](const IndexList& parents) {  // every 7th deformable surfel split
    exact->on_inserted(scene.view(), parents);
    approx->on_inserted(scene.view(), parents);
    const Index first = scene.rows() - static_cast<Index>(parents.size());
    for (std::size_t j = 0; j < parents.size(); ++j)
      EXPECT_EQ(approx->clusters().cluster_of(first + static_cast<Index>(j)), approx->clusters().cluster_of(parents[j]));
  };
  auto removed = [&](const std::vector<bool>& keep) {  // some zero and some deformable surfels dropped
    exact->on_removed(keep);
    approx->on_removed(keep);
  };
  testing::play_script(scene, slab_script(), edits, inserted, removed, [&](std::size_t k, const Points& previous) {
    approx->clusters().check();
    const CollisionResult want = exact->detect(scene.view(), previous);
    const CollisionResult got = approx->detect(scene.view(), previous);
    a.member_tests += got.stats.tested;
    a.exact_tests += want.stats.tested;
    a.queries += got.stats.queries;
    a.exact_queries += want.stats.queries;
    if (expect != Expect::Counts) {
      EXPECT_EQ(got.colliding, want.colliding) << to_string(cp.algorithm) << " step " << k;
      EXPECT_EQ(got.depths, want.depths) << to_string(cp.algorithm) << " step " << k;
    }
    if (expect == Expect::SameResultsAndTests)
      EXPECT_EQ(got.stats.tested, want.stats.tested) << to_string(cp.algorithm) << " step " << k;
    std::vector<char> hit(static_cast<std::size_t>(scene.rows()), 0);
    for (Index r : want.colliding) hit[r] = 1;
    std::size_t tp = 0;
    for (Index r : got.colliding) tp += hit[r];
    const std::size_t fp = got.colliding.size() - tp, fn = want.colliding.size() - tp;
    a.tp += tp;
    a.fp += fp;
    a.fn += fn;
    if (tp + fp) a.worst_precision = std::min(a.worst_precision, double(tp) / double(tp + fp));
    if (tp + fn) a.worst_recall = std::min(a.worst_recall, double(tp) / double(tp + fn));
  });
  return a;
}

SimplifyParams simplify_params(SimplifyMethod m, int size, double margin = 1.0) {
  SimplifyParams p;
  p.method = m;
  p.cluster_size = size;
  p.member_margin = margin;
  return p;
}

TEST(ApproximateDetection, ClusterSizeOneEqualsExactEveryStep) {
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Temporal, CollisionAlgorithm::Robust}) {
    for (auto m : {SimplifyMethod::RegionGrowing, SimplifyMethod::Hierarchical, SimplifyMethod::None}) {
      for (bool edits : {false, true}) {
        for (int threads : {1, 2}) {
          const Agreement g = run_side_by_side(slab_and_sphere(0.05), testing::params_of(a, threads),
                                               simplify_params(m, 1), edits, Expect::SameResultsAndTests);
          EXPECT_GT(g.tp, 100u) << to_string(a);  // the scene does collide
          EXPECT_EQ(g.fp + g.fn, 0u) << to_string(a);
        }
      }
    }
  }
}

// On a model of at least 16384 rows (at_once.hpp's kAtOnceMinPoints, an internal header) a reset on two threads makes
// the clusters beside the kernel's reset and seed: the same clusters, and the same results and counts at every step
// of the script (insertions and removals included) as the one-thread detector.
TEST(ApproximateDetection, ResetOnTwoThreadsEqualsOneThread) {
  constexpr Index kAtOnce = 16384;
  for (auto a : {CollisionAlgorithm::Simple, CollisionAlgorithm::Temporal, CollisionAlgorithm::Robust}) {
    for (auto m : {SimplifyMethod::RegionGrowing, SimplifyMethod::Hierarchical}) {
      SCOPED_TRACE(std::string(to_string(a)) +
                   (m == SimplifyMethod::RegionGrowing ? " region growing" : " hierarchical"));
      TestScene scene = slab_and_sphere(0.03);
      ASSERT_GE(scene.rows(), kAtOnce);
      auto one = make_approximate_detector(testing::params_of(a, 1), simplify_params(m, 18));
      auto two = make_approximate_detector(testing::params_of(a, 2), simplify_params(m, 18));
      one->reset(scene.view());
      two->reset(scene.view());
      ASSERT_EQ(two->clusters().cluster_count(), one->clusters().cluster_count());
      for (Index r = 0; r < scene.rows(); ++r) ASSERT_EQ(two->clusters().cluster_of(r), one->clusters().cluster_of(r));
      std::size_t colliding = 0;
      testing::play_script(
          scene, slab_script(), true,
          [&](const IndexList& parents) {
            one->on_inserted(scene.view(), parents);
            two->on_inserted(scene.view(), parents);
          },
          [&](const std::vector<bool>& keep) {
            one->on_removed(keep);
            two->on_removed(keep);
          },
          [&](std::size_t k, const Points& previous) {
            const CollisionResult want = one->detect(scene.view(), previous);
            testing::expect_same_detection(two->detect(scene.view(), previous), want, "step " + std::to_string(k));
            colliding += want.colliding.size();
          });
      EXPECT_GT(colliding, 0u);  // the scene does collide
    }
  }
}

TEST(ApproximateDetection, ImprovedIsRejectedNoneGivesNothing) {
  EXPECT_THROW(make_approximate_detector(testing::params_of(CollisionAlgorithm::Improved), SimplifyParams{}), Error);
  EXPECT_EQ(make_approximate_detector(testing::params_of(CollisionAlgorithm::None), SimplifyParams{}), nullptr);
  SimplifyParams bad;
  bad.cluster_size = 0;
  EXPECT_THROW(make_approximate_detector(testing::params_of(CollisionAlgorithm::Robust), bad), Error);
}

TEST(ApproximateDetection, PrecisionAndRecallAgainstExact) {
  // Spacing 0.04: ~1,950 deformable surfels on the ball, ~13,600 zero surfels on the slab.
  std::printf("[ approx ] algorithm method size margin: precision recall (over all steps; worst step) member tests / exact, queries / exact\n");
  for (auto a : {CollisionAlgorithm::Robust, CollisionAlgorithm::Temporal}) {
    for (auto m : {SimplifyMethod::Hierarchical, SimplifyMethod::RegionGrowing}) {
      for (int size : {1, 18, 100}) {
        for (double margin : {0.0, 1.0}) {
          // With the margin, on this scene (a ball through a slab): the exact detector's results at every step.
          // That covers the members of clusters that skipped steps (Robust: their old positions held, their
          // inside states re-derived there, RobustHeldState) when their clusters come near the slab again.
          const Agreement g = run_side_by_side(slab_and_sphere(0.04), testing::params_of(a, 2),
                                               simplify_params(m, size, margin), true,
                                               margin > 0.0 ? Expect::SameResults : Expect::Counts);
          std::printf("[ approx ] %-8s %-14s %3d %.0f: P %.4f R %.4f (worst %.3f %.3f) tests %zu / %zu, queries %zu / %zu\n",
                      to_string(a), to_string(m), size, margin, g.precision(), g.recall(), g.worst_precision,
                      g.worst_recall, g.member_tests, g.exact_tests, g.queries, g.exact_queries);
          if (size == 1) {
            EXPECT_EQ(g.fp + g.fn, 0u);
            continue;
          }
          // With the margin the members of every cluster near the slab are tested: the same results (checked
          // above). Without it (the thesis) clusters whose centroid has not yet entered miss their members.
          // Recall thresholds: measured figures (bench/RESULTS.md) minus a margin. Measured (spacing 0.04, both
          // algorithms, both clusterings), margin 0: R 0.93-0.94 at size 18, 0.85-0.88 at size 100 (the worst
          // single step: a cluster of 100 whose centroid is still outside while members are inside).
          // No false positive without the margin either: a member that skipped steps while its cluster entered the
          // slab is re-tested from its held old position (Robust, RobustHeldState), where it did not collide. A
          // skip that forgets that position makes P 0.49-0.76 (tried).
          EXPECT_EQ(g.fp, 0u);
          if (margin == 0.0) EXPECT_GE(g.recall(), size <= 18 ? 0.90 : 0.80);
          EXPECT_LT(g.member_tests, g.exact_tests);  // clusters did skip steps
        }
      }
    }
  }
}

// One factory for the session: the settings choose the approximate detector (simplification), a
// hierarchy's broad phase, the plain detector, or none.
TEST(ApproximateDetection, MakeDetectorFollowsTheSettings) {
  SessionSettings s;  // robust, no hierarchy, no simplification
  auto d = make_detector(s);
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(dynamic_cast<ApproximateDetector*>(d.get()), nullptr);
  EXPECT_EQ(d->hierarchy_info().status, "");
  s.hierarchy.zero = ZeroHierarchy::Aabb;
  d = make_detector(s);
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->hierarchy_info().status, "fresh");
  s.simplify.method = SimplifyMethod::Hierarchical;
  d = make_detector(s);
  EXPECT_NE(dynamic_cast<ApproximateDetector*>(d.get()), nullptr);
  s.collision.algorithm = CollisionAlgorithm::None;
  EXPECT_EQ(make_detector(s), nullptr);
}

}  // namespace
}  // namespace surfeledit
