// The merge response in a session (issue 9 §3; docs/algorithms.md §7 d): one history entry that undo
// restores bit for bit (clip lines and detector included), response "merge" on a colliding step,
// intersection curves, typed errors that change nothing, and later steps on the merged model.
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "session_fixture.hpp"

namespace surfeledit {
namespace {

// The default scene with its regions set (sphere deformable) and pushed `steps` x 0.1 down (the
// 4th step collides).
struct Pushed : SessionFixture {
  explicit Pushed(int steps = 4) {
    session.set_regions({zero, {}}, {one, {}});
    for (int k = 0; k < steps; ++k) session.deform(down(0.1));
  }
  static DeformParams down(double dz) {
    DeformParams p;
    p.translation = Vec3(0, 0, -dz);
    return p;
  }
};

// The code of the Error `f` throws; 0 when it throws none.
int code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return static_cast<int>(e.code());
  }
  return 0;
}

constexpr int kConflict = static_cast<int>(ErrorCode::Conflict);
constexpr int kInvalid = static_cast<int>(ErrorCode::InvalidArgument);

TEST(SessionMerge, OneHistoryEntryUndoneBitForBit) {
  Pushed f;
  ASSERT_FALSE(f.session.colliding().empty());
  const Snapshot before(f.session);
  const std::uint64_t v = f.session.version();
  const MergeOutcome m = f.session.merge(true);  // the tool that stepped (the default one) merges
  EXPECT_EQ(f.session.version(), v + 1);
  EXPECT_FALSE(m.removed.empty());
  EXPECT_FALSE(m.features.empty());
  EXPECT_FALSE(m.moved.empty());
  EXPECT_FALSE(m.curves.empty());
  EXPECT_TRUE(f.session.model().has_clips());
  EXPECT_TRUE(f.session.colliding().empty());
  for (SurfelId id : m.removed) EXPECT_LT(f.session.model().row_of(id), 0);
  for (SurfelId id : m.inserted) EXPECT_GE(f.session.model().row_of(id), 0);
  const std::vector<HistoryItem> h = f.session.history();
  EXPECT_EQ(h.back().op, "merge");
  EXPECT_EQ(h.back().author, "");
  const Snapshot after(f.session);
  f.session.undo();
  expect_same(Snapshot(f.session), before, "undo");
  f.session.redo();
  expect_same(Snapshot(f.session), after, "redo");
  // The detector came back with the model: undo, merge again -> the same merge.
  f.session.undo();
  const MergeOutcome again = f.session.merge(true);
  EXPECT_EQ(again.removed, m.removed);
  EXPECT_EQ(again.inserted, m.inserted);
  expect_same(Snapshot(f.session), after, "merge again");
}

TEST(SessionMerge, TypedErrorsChangeNothing) {
  SessionFixture f;  // no regions
  const Snapshot s(f.session);
  EXPECT_EQ(code_of([&] { f.session.merge(); }), kConflict);
  EXPECT_EQ(code_of([&] { f.session.intersection_curves(); }), kConflict);
  expect_same(Snapshot(f.session), s, "merge without regions");
  EXPECT_EQ(code_of([&] { f.session.configure({{"response", std::string("melt")}}); }), kInvalid);
  EXPECT_EQ(f.session.settings().response.mode, Response::Report);
  // Nothing colliding: an empty outcome, no entry, no new version.
  Pushed p(1);
  const std::uint64_t v = p.session.version();
  const std::size_t entries = p.session.history().size();
  const MergeOutcome m = p.session.merge();
  EXPECT_TRUE(m.removed.empty());
  EXPECT_EQ(p.session.version(), v);
  EXPECT_EQ(p.session.history().size(), entries);
  // Curve parameters are validated.
  Pushed q;
  q.session.merge();
  CurveParams bad;
  bad.refine_angle = -1.0;
  EXPECT_EQ(code_of([&] { q.session.intersection_curves(bad); }), kInvalid);
  CurveParams fine;
  fine.refine_angle = 0.2;
  const std::vector<Curve> curves = q.session.intersection_curves(fine);
  ASSERT_FALSE(curves.empty());
  for (const Curve& c : curves) EXPECT_GE(c.points.rows(), 3);
}

TEST(SessionMerge, ResponseMergeOnAStepThenLaterStepsAndDetection) {
  Pushed f(3);
  f.session.configure({{"response", std::string("merge")}});
  const Snapshot before(f.session);
  const StepResult r = f.session.deform(Pushed::down(0.1));
  EXPECT_EQ(r.response, "merged");
  EXPECT_FALSE(r.colliding.empty());  // what collided (the merge removed it)
  EXPECT_FALSE(r.features.empty());
  EXPECT_TRUE(f.session.colliding().empty());
  EXPECT_TRUE(f.session.model().has_clips());
  for (Index row : r.moved) EXPECT_LT(row, f.session.model().size());
  // The detector re-initialised from the merged model: a step up separates, a step down collides again.
  const StepResult up = f.session.deform(Pushed::down(-0.05));
  EXPECT_EQ(up.response, "none");
  f.session.configure({{"response", std::string("report")}});
  f.session.deform(Pushed::down(0.05));
  const StepResult deeper = f.session.deform(Pushed::down(0.1));
  EXPECT_TRUE(deeper.detected);
  EXPECT_FALSE(deeper.colliding.empty());
  // Undo back over the merged step (5 entries: step, step, configure, step, step).
  for (int k = 0; k < 5; ++k) f.session.undo();
  expect_same(Snapshot(f.session), before, "undo of the merged step");
}

TEST(SessionMerge, RandomSequencesAgainstSnapshots) {
  Pushed f(2);
  std::mt19937 rng(11);
  UndoChecker stack;
  int merges = 0;
  for (int it = 0; it < 40; ++it) {
    const int what = static_cast<int>(rng() % 10);
    if (what < 4) {
      Snapshot b(f.session);
      f.session.deform(Pushed::down(0.04 + 0.02 * static_cast<double>(rng() % 4)));
      stack.applied(std::move(b));
    } else if (what < 6) {
      const std::uint64_t v = f.session.version();
      Snapshot b(f.session);
      f.session.merge(rng() % 2 == 0);
      if (f.session.version() == v) continue;  // nothing collided
      stack.applied(std::move(b));
      ++merges;
    } else if (what < 9) {
      stack.undo(f.session, std::to_string(it));
    } else {
      stack.redo(f.session, std::to_string(it));
    }
  }
  EXPECT_GT(merges, 0);
}

}  // namespace
}  // namespace surfeledit
