// The detectors' step journal (row_detector.hpp, Journal): the states a step's sweeps change are kept in
// one part per chunk of rows, in sequence, and the history's image of them is the parts in row order. Truth:
// a fresh session given only the steps still applied (undo must bring the detector's hidden states back:
// a probe step then finds the same colliding ids and depths, bit for bit, with the same work), and the same steps at one
// thread (two threads, with the sweep parallel at every size, must give the same bytes). Back-off makes
// journals of several sweeps (the step is taken back and re-swept within one journal).
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "session_fixture.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {

using Config = std::vector<NamedSetting>;

// The default scene at a spacing that gives the sphere (F1) a few thousand surfels: several sweep chunks.
struct Drag {
  EditSession session;
  IdList zero, one;
  Drag(int threads, const Config& config) : session("t", SessionParams{threads}) {
    const SampledSurfels s = make_default_scene().sample(SampleParams{0.035, 3, 0.25});
    SurfelArrays a;
    a.positions = s.positions;
    a.normals = s.normals;
    a.radii = s.radii;
    session.load(SurfelModel::from_arrays(a));
    for (std::size_t i = 0; i < s.part.size(); ++i) (s.part[i] == 0 ? zero : one).push_back(i);
    session.set_regions({zero, {}}, {one, {}});
    Config c = config;
    c.push_back({"threads", threads});
    c.push_back({"parallel_min_ms", 0.0});  // the parallel sweep whatever the work
    session.configure(c);
  }
};

DeformParams down(int k) {
  DeformParams p;
  p.translation = Vec3(0.004 * (k % 3 - 1), 0.0, -0.06);
  p.angle = 0.02 * (k % 2 ? 1 : -1);
  p.axis = Vec3(1, 0, 0);
  return p;
}

struct Probe {
  IdList colliding;
  std::vector<double> depths;
  std::string response;
  Index tested = 0, queries = 0;  // the detector's work: points whose state it re-evaluated, its queries
};

// The step after the ones kept (k): the one that first collided in the drag.
Probe probe(EditSession& s, int k) {
  const StepResult r = s.deform(down(k));
  return {r.colliding, r.depths, r.response, r.stats.tested, r.stats.queries};
}

class DetectorJournal : public ::testing::TestWithParam<std::string> {};

TEST_P(DetectorJournal, UndoneStepsGiveBackTheDetectorStatesAtOneAndTwoThreads) {
  const std::string response = GetParam();
  constexpr int kCollided = 3, kMaxSteps = 40;
  // The hierarchical detector keeps the narrow phase's journal (its rows outside the broad phase too).
  const std::vector<std::pair<std::string, Config>> configs = {
      {"temporal", {{"algorithm", std::string("temporal")}}},
      {"simple", {{"algorithm", std::string("simple")}}},
      {"robust", {{"algorithm", std::string("robust")}}},
      {"robust with a zero tree", {{"algorithm", std::string("robust")}, {"zero_hierarchy", std::string("aabb")}}},
      {"robust with two trees",
       {{"algorithm", std::string("robust")}, {"zero_hierarchy", std::string("obb")},
        {"deformable_hierarchy", std::string("aabb")}}},
  };
  for (const auto& [algorithm, settings] : configs) {
    Config config = settings;
    config.push_back({"response", response});
    std::vector<Probe> by_threads;
    std::vector<std::vector<IdList>> steps_by_threads;
    for (int threads : {1, 2}) {
      SCOPED_TRACE(algorithm + " " + response + ", threads " + std::to_string(threads));
      // Down until kCollided steps collided; then the collided steps are undone.
      Drag a(threads, config);
      std::vector<IdList> colliding;
      int steps = 0, collided = 0;
      while (collided < kCollided && steps < kMaxSteps) {
        const StepResult r = a.session.deform(down(steps++));
        ASSERT_NE(r.response, "cancelled");
        colliding.push_back(r.colliding);
        collided += r.response != "none";
      }
      ASSERT_EQ(collided, kCollided) << "the drag never collided";
      const int kept = steps - kCollided;
      ASSERT_GT(kept, 0);
      for (int k = 0; k < kCollided; ++k) a.session.undo();
      Drag b(threads, config);  // a fresh session given the kept steps only
      for (int k = 0; k < kept; ++k) b.session.deform(down(k));
      expect_same(Snapshot(a.session), Snapshot(b.session), "after the undos");
      const Probe pa = probe(a.session, kept), pb = probe(b.session, kept);
      EXPECT_EQ(pa.colliding, pb.colliding);
      EXPECT_EQ(pa.depths, pb.depths);
      EXPECT_EQ(pa.response, pb.response);
      // A state put back wrong shows in the work too (a Temporal sphere of the undone steps is re-tested).
      EXPECT_EQ(pa.tested, pb.tested);
      EXPECT_EQ(pa.queries, pb.queries);
      EXPECT_NE(pa.response, "none") << "the probe should collide";
      expect_same(Snapshot(a.session), Snapshot(b.session), "after the probe");
      by_threads.push_back(pa);
      steps_by_threads.push_back(colliding);
    }
    EXPECT_EQ(steps_by_threads[0], steps_by_threads[1]) << algorithm;
    EXPECT_EQ(by_threads[0].colliding, by_threads[1].colliding) << algorithm;
    EXPECT_EQ(by_threads[0].depths, by_threads[1].depths) << algorithm;
  }
}

INSTANTIATE_TEST_SUITE_P(Responses, DetectorJournal, ::testing::Values("report", "backoff"));

}  // namespace
}  // namespace surfeledit
