// Edit history (issue 9 §1) and the cancel response (§2): undo / redo restore the state before / after
// each op bit for bit, checked against independent copies of the arrays taken before each op.
#include <gtest/gtest.h>

#include <random>

#include "surfeledit/core/edit_session.hpp"
#include "session_fixture.hpp"

namespace surfeledit {
namespace {

// The default scene (slab + sphere 0.35 above it) with its regions set, sphere deformable.
struct HistoryFixture : SessionFixture {
  HistoryFixture() : SessionFixture("alice") { session.set_regions({zero, {}}, {one, {}}); }
};

DeformParams down(double dz) {
  DeformParams p;
  p.translation = Vec3(0, 0, -dz);
  return p;
}

TEST(History, UndoRedoOfStepsIsBitExact) {
  HistoryFixture f;
  const Snapshot s0(f.session);
  std::vector<Snapshot> after;
  std::vector<StepResult> results;
  for (int k = 0; k < 5; ++k) {  // the 4th and 5th steps collide
    results.push_back(f.session.deform(down(0.1)));
    after.emplace_back(f.session);
  }
  ASSERT_FALSE(results.back().colliding.empty());
  const std::uint64_t v = f.session.version();
  for (int k = 4; k >= 0; --k) {
    EXPECT_EQ(f.session.undo(), v + static_cast<std::uint64_t>(5 - k));
    expect_same(Snapshot(f.session), k > 0 ? after[static_cast<std::size_t>(k - 1)] : s0, "undo " + std::to_string(k));
  }
  for (int k = 0; k < 5; ++k) {
    f.session.redo();
    expect_same(Snapshot(f.session), after[static_cast<std::size_t>(k)], "redo " + std::to_string(k));
  }
  // The detector state came back too: undo twice and step again -> the same results as the first time.
  f.session.undo();
  f.session.undo();
  for (int k = 3; k < 5; ++k) {
    const StepResult r = f.session.deform(down(0.1));
    EXPECT_EQ(r.colliding, results[static_cast<std::size_t>(k)].colliding);
    EXPECT_EQ(r.depths, results[static_cast<std::size_t>(k)].depths);
    expect_same(Snapshot(f.session), after[static_cast<std::size_t>(k)], "re-step");
  }
  EXPECT_THROW(f.session.redo(), Error);  // a new op dropped the redo tail
}

TEST(History, EntriesListVersionOpAuthorTouched) {
  SessionFixture f("alice");  // bob sets regions of his own tool and steps with it (issue 11)
  f.session.set_regions({f.zero, {}}, {f.one, {}}, "bob");
  f.session.deform(down(0.1), "bob");
  const std::vector<HistoryItem> h = f.session.history();
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0].op, "load");
  EXPECT_EQ(h[0].author, "alice");
  EXPECT_EQ(h[1].op, "set_regions");
  EXPECT_EQ(h[1].author, "bob");
  EXPECT_EQ(h[2].op, "deform");
  EXPECT_EQ(h[2].author, "bob");
  EXPECT_EQ(h[2].version, f.session.version());
  EXPECT_EQ(h[2].touched, f.one);
  f.session.undo();
  EXPECT_TRUE(f.session.history()[2].undone);
  // The undone rows count as changed since the step.
  EXPECT_EQ(f.session.changes_since(h[2].version).changed, f.one);
}

TEST(History, NothingToUndoIsConflict) {
  EditSession s("empty");
  try {
    s.undo();
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Conflict);
  }
  EXPECT_THROW(s.redo(), Error);
}

TEST(History, RandomSequencesAgainstSnapshots) {
  HistoryFixture f;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  UndoChecker stack;
  const char* responses[] = {"report", "cancel", "report"};
  for (int it = 0; it < 60; ++it) {
    const int what = static_cast<int>(rng() % 10);
    if (what < 4) {
      Snapshot b(f.session);
      DeformParams p = down(0.05 + 0.05 * (u(rng) + 1));
      p.angle = 0.2 * u(rng);
      p.axis = Vec3(1, 0, 0);
      const StepResult r = f.session.deform(p);
      if (r.response == "cancelled") {
        expect_same(Snapshot(f.session), b, "cancel");
        continue;
      }
      stack.applied(std::move(b));
    } else if (what < 5) {
      const IdList& ids = f.session.model().ids();
      const SurfelId id = ids[rng() % ids.size()];
      if (id == f.zero.front() || id == f.one.front()) continue;  // keep both regions non-empty
      Snapshot b(f.session);
      f.session.remove({id});
      stack.applied(std::move(b));
    } else if (what < 6) {
      Snapshot b(f.session);
      f.session.configure({{"response", std::string(responses[rng() % 3])}});
      stack.applied(std::move(b));
    } else if (what < 9 && !stack.before.empty()) {
      stack.undo(f.session, std::to_string(it));
    } else {
      stack.redo(f.session, std::to_string(it));
    }
  }
}

TEST(History, MemoryIsBoundedAndReported) {
  HistoryFixture f;
  f.session.configure({{"history_mb", 0.0}});
  f.session.deform(down(0.1));
  EXPECT_TRUE(f.session.history().empty());
  EXPECT_THROW(f.session.undo(), Error);
  bool listed = false;
  for (const auto& s : f.session.report().structures) listed |= s.name == "history";
  EXPECT_TRUE(listed);
}

TEST(Response, CancelRestoresTheStateBitForBit) {
  HistoryFixture f;
  f.session.configure({{"response", std::string("cancel")}});
  for (int k = 0; k < 3; ++k) EXPECT_EQ(f.session.deform(down(0.1)).response, "none");
  const Snapshot b(f.session);
  const std::uint64_t v = f.session.version();
  const StepResult r = f.session.deform(down(0.1));
  EXPECT_EQ(r.response, "cancelled");
  EXPECT_FALSE(r.colliding.empty());  // what would have collided
  expect_same(Snapshot(f.session), b, "cancelled");
  EXPECT_EQ(f.session.version(), v);
  // The detector is exactly as before: a smaller step that does not collide behaves as without the
  // cancelled one, and the same step is cancelled again with the same report.
  const StepResult again = f.session.deform(down(0.1));
  EXPECT_EQ(again.colliding, r.colliding);
  EXPECT_EQ(again.depths, r.depths);
}

TEST(Response, BadSettingsAreTypedAndChangeNothing) {
  HistoryFixture f;
  f.session.deform(down(0.1));
  const Snapshot b(f.session);
  const std::uint64_t v = f.session.version();
  const std::size_t entries = f.session.history().size();
  const std::pair<NamedSetting, const char*> bad[] = {
      {{"response", std::string("melt")}, "response"},
      {{"backoff_epsilon", -1.0}, "backoff_epsilon"},
      {{"backoff_max_iterations", 0}, "backoff_max_iterations"},
      {{"history_mb", -2.0}, "history_mb"},
  };
  for (const auto& [setting, field] : bad) {
    try {
      f.session.configure({setting});
      ADD_FAILURE() << field << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidArgument) << field;
      EXPECT_EQ(e.field(), field);
    }
    expect_same(Snapshot(f.session), b, field);
    EXPECT_EQ(f.session.version(), v);
    EXPECT_EQ(f.session.history().size(), entries);
  }
}

}  // namespace
}  // namespace surfeledit
