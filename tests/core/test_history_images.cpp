// History images hold what their op needs (issue 14, memory): set_regions / configure / release keep a
// tool image only (nothing model-sized), and a detector that a reset from the same model reproduces is
// re-derived rather than kept. Checked against sessions that never took the undone op (a replay), and
// the report's split of the history by image kind.
#include <gtest/gtest.h>

#include "session_fixture.hpp"
#include "surfeledit/core/edit_session.hpp"

namespace surfeledit {
namespace {

DeformParams down_turned(double dz) {
  DeformParams p;
  p.translation = Vec3(0, 0, -dz);
  p.angle = 0.05;
  p.axis = Vec3(1, 0, 0);
  return p;
}

struct StepsRun {
  std::vector<IdList> colliding;
  std::vector<std::vector<double>> depths;
  Points positions;
};

// Five steps (the last ones collide) and what they found.
StepsRun steps(EditSession& s) {
  StepsRun r;
  for (int k = 0; k < 5; ++k) {
    const StepResult out = s.deform(down_turned(0.1));
    r.colliding.push_back(out.colliding);
    r.depths.push_back(out.depths);
  }
  r.positions = s.model().positions();
  return r;
}

void expect_same_run(const StepsRun& a, const StepsRun& b) {
  EXPECT_EQ(a.colliding, b.colliding);
  EXPECT_EQ(a.depths, b.depths);  // exact: the detectors' states are the same bit for bit
  EXPECT_TRUE(a.positions == b.positions);
  ASSERT_FALSE(a.colliding.back().empty());  // the test means something: the last steps collide
}

const SessionReport::HistoryKind& kind(const SessionReport& r, const std::string& k) {
  for (const auto& h : r.history_kinds)
    if (h.kind == k) return h;
  throw std::runtime_error("no history kind " + k);
}

std::size_t structure(const SessionReport& r, const std::string& name) {
  std::size_t b = 0;
  for (const auto& s : r.structures)
    if (s.name == name) b += s.bytes;
  return b;
}

TEST(HistoryImages, ToolOpsHoldNoModelSizedImage) {
  SessionFixture f;
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  f.session.configure({{"algorithm", std::string("temporal")}});
  f.session.release();
  const SessionReport r = f.session.report();
  EXPECT_EQ(kind(r, "tool").entries, 3u);
  EXPECT_EQ(kind(r, "whole").entries, 1u);  // the load (into an empty session)
  EXPECT_EQ(kind(r, "rows").entries, 0u);
  const std::size_t model = structure(r, "model");
  // The release keeps the fields and the (stepped-never, so re-derived) detector out: the images of the
  // three tool ops together hold less than the fields and a tenth of the model.
  EXPECT_LT(kind(r, "tool").bytes, model / 2);
  EXPECT_LT(kind(r, "whole").bytes, model / 10);
  EXPECT_EQ(kind(r, "tool").bytes + kind(r, "whole").bytes + kind(r, "rows").bytes, structure(r, "history"));
}

TEST(HistoryImages, UndoOfConfigureRederivesTheDetectorExactly) {
  // Reference: a session that never configured.
  SessionFixture ref;
  ref.session.set_regions({ref.zero, {}}, {ref.one, {}});
  const StepsRun expected = steps(ref.session);

  SessionFixture f;
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  f.session.configure({{"algorithm", std::string("simple")}});
  f.session.undo();  // the Robust detector comes back, re-derived from the model
  EXPECT_EQ(f.session.settings().collision.algorithm, CollisionAlgorithm::Robust);
  expect_same_run(steps(f.session), expected);
}

TEST(HistoryImages, RedoOfConfigureAfterUndoneStepsMatchesAReplay) {
  SessionFixture ref;
  ref.session.set_regions({ref.zero, {}}, {ref.one, {}});
  ref.session.configure({{"algorithm", std::string("temporal")}});
  const StepsRun expected = steps(ref.session);

  SessionFixture f;
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  f.session.configure({{"algorithm", std::string("temporal")}});
  f.session.deform(down_turned(0.1));
  f.session.deform(down_turned(0.1));
  f.session.undo();
  f.session.undo();
  f.session.undo();  // configure: its after-image keeps the stepped-and-restored detector object
  f.session.undo();  // set_regions
  f.session.redo();
  f.session.redo();
  EXPECT_EQ(f.session.settings().collision.algorithm, CollisionAlgorithm::Temporal);
  // A new op drops the redo tail (the two steps): the detector goes on from its state after configure.
  expect_same_run(steps(f.session), expected);
}

TEST(HistoryImages, UndoOfReleaseBringsRegionsAndDetectorBack) {
  SessionFixture ref;
  ref.session.set_regions({ref.zero, {}}, {ref.one, {}});
  const StepsRun expected = steps(ref.session);

  SessionFixture f;
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  EXPECT_TRUE(f.session.release());
  EXPECT_FALSE(f.session.has_regions());
  f.session.undo();
  ASSERT_TRUE(f.session.has_regions());
  EXPECT_EQ(f.session.fields()->deformable.size(), ref.session.fields()->deformable.size());
  expect_same_run(steps(f.session), expected);
}

TEST(HistoryImages, AStepMakesTheDetectorNotDerivable) {
  // After a step the detector's states are its own: configure's image keeps the object, and undoing
  // configure gives back that object (later steps continue as if configure never happened).
  SessionFixture ref;
  ref.session.set_regions({ref.zero, {}}, {ref.one, {}});
  const StepsRun expected = steps(ref.session);

  SessionFixture f;
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  const StepResult first = f.session.deform(down_turned(0.1));
  const std::size_t robust = structure(f.session.report(), "collision_robust");  // the object the image must keep
  f.session.configure({{"algorithm", std::string("simple")}});
  EXPECT_GT(kind(f.session.report(), "tool").bytes, robust);
  f.session.undo();
  StepsRun r;
  r.colliding.push_back(first.colliding);
  r.depths.push_back(first.depths);
  for (int k = 1; k < 5; ++k) {
    const StepResult out = f.session.deform(down_turned(0.1));
    r.colliding.push_back(out.colliding);
    r.depths.push_back(out.depths);
  }
  r.positions = f.session.model().positions();
  expect_same_run(r, expected);
}

}  // namespace
}  // namespace surfeledit
