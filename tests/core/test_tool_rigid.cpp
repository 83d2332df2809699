// A tool's detector follows the rows other tools move (issue 11 §1, third point; docs/collaboration.md
// "What a tool's detector treats as rigid"): CollisionDetector::on_rigid_moved at the tool's next step
// instead of a re-initialisation. Truth: the exact signed distances of the analytic capsules and box the
// two-arm scene is sampled from (core/two_arms.hpp), a detector built fresh on the same model, and a
// session that re-initialises (SessionParams::incremental_rigid = false).
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "surfeledit/core/collision.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/snapshot_io.hpp"
#include "surfeledit/core/two_arms.hpp"

namespace surfeledit {
namespace {

constexpr double kRigidSpacing = 0.02;

struct Swing {
  TwoArms scene{SampleParams{kRigidSpacing, 7, 0.25}};
  EditSession session;
  Vec3 offset_a = Vec3::Zero(), offset_b = Vec3::Zero();  // where each tool moved its arm

  Swing(const std::vector<NamedSetting>& settings, bool incremental) : session("swing", params(incremental)) {
    session.load(scene.model());
    for (const char* tool : {"a", "b"}) session.configure(settings, tool);
    session.set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
    session.set_regions({TwoArms::join(scene.body, scene.a), {}}, {scene.b, {}}, "b");
  }
  static SessionParams params(bool incremental) {
    SessionParams p;
    p.threads = 2;
    p.incremental_rigid = incremental;
    return p;
  }
  StepResult move(const std::string& tool, double dx) {
    DeformParams p;
    p.translation = Vec3(dx, 0, 0);
    (tool == "a" ? offset_a : offset_b) += p.translation;
    return session.deform(p, tool);
  }
  // One step of the swing: arm a moves by +0.05, arm b by -0.05 (towards each other).
  StepResult swing(const std::string& tool) { return move(tool, tool == "a" ? 0.05 : -0.05); }
};

// Steps `tool` in both sessions and expects the same colliding ids and depths; returns x's result.
StepResult expect_same_step(Swing& x, Swing& y, const std::string& tool, int k) {
  const StepResult rx = x.swing(tool);
  const StepResult ry = y.swing(tool);
  EXPECT_EQ(rx.colliding, ry.colliding) << tool << " step " << k;
  EXPECT_EQ(rx.depths, ry.depths) << tool << " step " << k;
  return rx;
}

// Checks a tool's colliding set against the exact solids where they are now: every surfel of its arm
// deeper than `tol` inside the other arm (farther than 0.1 from the body) is reported, every reported one
// lies within `tol` of the other arm or the body (or inside). Returns how many were that deep (so that a check is not vacuous).
std::size_t expect_exact(const Swing& s, const std::string& tool, const IdList& colliding, const std::string& where) {
  SCOPED_TRACE(where);
  const bool a = tool == "a";
  const auto other = a ? TwoArms::arm_b_solid(s.offset_b) : TwoArms::arm_a_solid(s.offset_a);
  const auto body = TwoArms::body_solid();
  const double tol = 2.0 * kRigidSpacing;
  const SurfelModel& m = s.session.model();
  const std::set<SurfelId> found(colliding.begin(), colliding.end());
  std::size_t deep = 0;
  for (SurfelId id : a ? s.scene.a : s.scene.b) {
    const Vec3 p = m.positions().row(m.row_of(id)).transpose();
    const double d = std::min(other->sdf(p), body->sdf(p));
    // Within 0.1 of the body (where the arms stand on it) the nearest zero surfel of a surfel deep in the
    // other arm may be the body's face, which every nearest-surfel test reads as outside: not checked.
    if (d < -tol && body->sdf(p) > 0.1) {
      ++deep;
      EXPECT_TRUE(found.count(id)) << tool << ": surfel " << id << " is " << -d << " deep but not reported, at " << p.transpose();
    }
    if (found.count(id)) EXPECT_LT(d, tol) << tool << ": surfel " << id << " reported at distance " << d;
  }
  return deep;
}

// The two arms swung into each other, each by its own tool, alternately (a by 0.05, b by 0.04 a step: no
// test finds a surfel closer to the other surface than the sampling's jitter), until they overlap by 0.07
// (less than the arms' radius: beyond the other arm's axis the nearest-surfel tests see its far side), then back out. After
// every step both tools' colliding sets agree with the exact solids (the other arm where the other tool
// moved it): Robust and Temporal keep their states across the other tool's steps, so a surfel stays
// reported for as long as it is inside, whichever arm moved last.
void swing(const std::string& algorithm) {
  SCOPED_TRACE(algorithm);
  Swing s({{"algorithm", algorithm}}, true);
  std::vector<std::pair<std::string, double>> in;
  // Arm A's axis at x = -0.4, arm B's at +0.4, radius 0.1: they touch after 0.6 of travel in all.
  for (int k = 0; k < 7; ++k) {
    in.emplace_back("b", -0.04);
    in.emplace_back("a", 0.05);
  }
  in.emplace_back("b", -0.04);  // overlap 0.07
  in.emplace_back("a", 0.0);     // a sees where b's arm came
  std::size_t deep = 0;
  int k = 0;
  for (const auto& [tool, dx] : in) {
    const StepResult r = s.move(tool, dx);
    ASSERT_TRUE(r.detected);
    deep += expect_exact(s, tool, r.colliding, tool + " in, step " + std::to_string(k++));
    EXPECT_EQ(s.session.colliding(tool), r.colliding);
  }
  EXPECT_GT(deep, 20u);
  for (auto it = in.rbegin(); it != in.rbegin() + 6; ++it) {
    const StepResult r = s.move(it->first, -it->second);
    expect_exact(s, it->first, r.colliding, it->first + " out, step " + std::to_string(k++));
  }
}

TEST(ToolRigid, ArmsSwungIntoEachOtherRobust) { swing("robust"); }
TEST(ToolRigid, ArmsSwungIntoEachOtherTemporal) { swing("temporal"); }
TEST(ToolRigid, ArmsSwungIntoEachOtherSimple) { swing("simple"); }
TEST(ToolRigid, ArmsSwungIntoEachOtherImproved) { swing("improved"); }

// The arm of the other tool moves onto surfels that stand still: they are reported at the tool's next
// step (a step of 0: nothing of its own moves), by the incremental update -- a re-initialisation makes
// the model as it is then the original one and reports nothing (the documented limit of a reset).
TEST(ToolRigid, TheOtherArmMovingOntoStillSurfelsIsDetectedRobust) {
  Swing s({{"algorithm", std::string("robust")}}, true);
  Swing reset({{"algorithm", std::string("robust")}}, false);
  for (Swing* x : {&s, &reset}) {
    x->move("a", 0.3);   // arm A's front at x = -0.0
    x->move("b", -0.35);  // arm B's front at x = -0.05: 0.05 into arm A
  }
  const StepResult r = s.move("a", 0.0);
  EXPECT_GT(expect_exact(s, "a", r.colliding, "incremental"), 5u);
  EXPECT_TRUE(reset.move("a", 0.0).colliding.empty());
}

// Simple without step bound and boundary marks is a function of the positions alone: after every step
// of the swing, the tool's colliding set equals that of a detector built fresh on the model as it is,
// and that of a session that re-initialises the detector instead of updating it.
TEST(ToolRigid, SimpleEqualsAFreshDetectorAndTheReinitialisation) {
  const std::vector<NamedSetting> settings = {
      {"algorithm", std::string("simple")}, {"step_bound", false}, {"boundary", false}};
  Swing s(settings, true), reset(settings, false);
  std::size_t reported = 0;
  for (int k = 0; k < 10; ++k) {
    for (const char* tool : {"b", "a"}) {
      const StepResult r = expect_same_step(s, reset, tool, k);
      // A fresh detector on the same model; `previous` is irrelevant without the step bound.
      const SurfelModel& m = s.session.model();
      const DeformationFields& f = *s.session.fields(tool);
      auto fresh = make_detector(s.session.settings(tool));
      const CollisionScene scene{m.positions(), m.normals(), m.radii(), f.regions};
      fresh->reset(scene);
      const CollisionResult c = fresh->detect(scene, m.positions());
      IdList ids;
      for (Index row : c.colliding) ids.push_back(m.id_of(row));
      EXPECT_EQ(r.colliding, ids) << tool << " step " << k;
      reported += ids.size();
    }
  }
  EXPECT_GT(reported, 50u);
}

// Undo and redo stay exact with incremental updates: an undone and redone step (of either tool) leaves
// every tool's next step exactly as in a session where neither happened.
TEST(ToolRigid, UndoRedoLeavesTheNextStepsUnchanged) {
  for (const std::string algorithm : {"robust", "temporal"}) {
    SCOPED_TRACE(algorithm);
    Swing x({{"algorithm", algorithm}}, true), y({{"algorithm", algorithm}}, true);
    for (int k = 0; k < 9; ++k) {
      for (const char* tool : {"b", "a"}) {
        expect_same_step(x, y, tool, k);
        if (k % 3 == 1) {
          x.session.undo(tool);
          x.session.redo(tool);
        }
        EXPECT_EQ(x.session.state_hash(), y.session.state_hash());
      }
    }
  }
}

// An undo that brings back an older detector object (the entry's own part, another tool changed rows
// since) re-initialises it at the next step, and the tool still sees the other arm where it is now.
TEST(ToolRigid, AnOwnPartUndoFallsBackToTheReinitialisation) {
  Swing s({{"algorithm", std::string("robust")}}, true);
  for (int k = 0; k < 6; ++k) {
    s.move("a", 0.05);
    s.move("b", -0.05);
  }
  s.session.undo("a");  // b stepped since: a's own part comes back
  s.offset_a -= Vec3(0.05, 0, 0);
  const StepResult r = s.move("a", 0.1);
  EXPECT_GT(expect_exact(s, "a", r.colliding, "after the undo"), 5u);
}

// A stale tool's detector follows the other tool's moves on a clone while history images still refer to
// the old object (EditSession::sync_tool); the history's bound counts those objects once no tool holds
// them, so alternating steps cannot grow the history past history_mb (before, each step of the swing
// left one more whole detector in it, uncounted).
TEST(ToolRigid, TheHistoryBoundCountsTheDetectorsItKeepsAlive) {
  Swing s({{"algorithm", std::string("robust")}}, true);
  const auto report_of = [&] {
    struct {
      std::size_t history = 0, detector = 0, held_objects = 0, held_bytes = 0, kinds = 0;
    } r;
    const SessionReport rep = s.session.report();
    for (const auto& st : rep.structures) {
      if (st.name == "history") r.history = st.bytes;
      if (st.name == "collision_robust") r.detector = std::max(r.detector, st.bytes);  // one per tool
    }
    for (const auto& k : rep.history_kinds) {
      r.kinds += k.bytes;
      if (k.kind == "detectors") r.held_objects = k.entries, r.held_bytes = k.bytes;
    }
    return r;
  };
  for (int k = 0; k < 4; ++k) {
    s.move("a", 0.01);
    s.move("b", -0.01);
  }
  const auto unbounded = report_of();
  // Each alternating step after the first left the object its tool followed from.
  ASSERT_GE(unbounded.held_objects, 5u);
  EXPECT_GE(unbounded.held_bytes, unbounded.held_objects * unbounded.detector * 9 / 10);
  EXPECT_EQ(unbounded.kinds, unbounded.history);

  // A bound of about three detectors: it holds after every step, and the newest steps still undo.
  const double mb = 3.0 * static_cast<double>(unbounded.detector) / (1024.0 * 1024.0);
  s.session.configure({{"history_mb", mb}}, "a");
  const std::size_t limit = static_cast<std::size_t>(mb * 1024.0 * 1024.0);
  for (int k = 0; k < 6; ++k) {
    s.move("a", 0.01);
    s.move("b", -0.01);
    const auto r = report_of();
    EXPECT_LE(r.history, limit) << "round " << k;
    EXPECT_LE(r.held_objects, 3u) << "round " << k;
  }
  const std::uint64_t hash = s.session.state_hash();
  s.session.undo("b");
  EXPECT_NE(s.session.state_hash(), hash);
  s.session.redo("b");
  EXPECT_EQ(s.session.state_hash(), hash);
}

// A stale tool keeps what the other tool's step moved as its detector saw it (Tool::hold_rigid: Robust keeps no
// copy of its zero rows, issue 14); the session snapshot keeps it too: a restored session's next steps equal
// the never-saved one's; the held rows are listed in the session report.
TEST(ToolRigid, ASnapshotOfAStaleToolKeepsWhereTheMovedRowsWere) {
  Swing x({{"algorithm", std::string("robust")}}, true);
  for (int k = 0; k < 3; ++k) {
    x.swing("a");
    x.swing("b");
  }
  x.swing("a");
  x.swing("a");  // b is stale: a's arm moved twice since b's detector saw it
  const auto held = [](const EditSession& s) {
    std::size_t bytes = 0;
    for (const auto& st : s.report().structures)
      if (st.name == "rigid_held") bytes += st.bytes;
    return bytes;
  };
  const std::size_t a_rows = x.session.fields("a")->deformable.size();
  EXPECT_GE(held(x.session), a_rows * 7 * sizeof(double));  // positions, normals, radius per moved row

  SnapshotWriter w;
  x.session.save(w);
  EditSession z{"swing", Swing::params(true)};
  SnapshotReader r(w.bytes());
  z.restore(r);
  EXPECT_EQ(held(z), held(x.session));
  DeformParams p;
  p.translation = Vec3(-0.05, 0, 0);
  for (int k = 0; k < 3; ++k) {
    const StepResult rx = x.session.deform(p, "b");
    const StepResult rz = z.deform(p, "b");
    EXPECT_EQ(rx.colliding, rz.colliding) << k;
    EXPECT_EQ(rx.depths, rz.depths) << k;
  }
  EXPECT_EQ(x.session.state_hash(), z.state_hash());
}

}  // namespace
}  // namespace surfeledit
