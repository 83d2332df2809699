// Tools (issue 11 §1): one tool per author in a session, locks on the rows a tool can move, release,
// and a tool's detector seeing another tool's moves. Truth: exact signed distances of the analytic
// capsules the arms are sampled from, and sets computed here from the regions.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "expect_error.hpp"
#include "session_fixture.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/tool.hpp"
#include "surfeledit/core/two_arms.hpp"

namespace surfeledit {
namespace {

using testing_util::expect_error;

// The two-arm scene (core/two_arms.hpp) in a session: tool "a" moves arm A (its zero region: body and
// arm B), tool "b" arm B.
struct ArmsSession {
  static constexpr double kSpacing = 0.02;
  TwoArms scene{SampleParams{kSpacing, 7, 0.25}};
  EditSession session{"arms"};
  const IdList& body = scene.body;
  const IdList& a = scene.a;
  const IdList& b = scene.b;

  explicit ArmsSession(SessionParams params = {}) : session("arms", params) { session.load(scene.model()); }
  void take_tools() {
    session.set_regions({TwoArms::join(body, b), {}}, {a, {}}, "a");
    session.set_regions({TwoArms::join(body, a), {}}, {b, {}}, "b");
  }
  StepResult move(const std::string& tool, double dx) {
    DeformParams p;
    p.translation = Vec3(dx, 0, 0);
    return session.deform(p, tool);
  }
};

IdList sorted(IdList v) {
  std::sort(v.begin(), v.end());
  return v;
}

TEST(Tool, EachAuthorHasItsOwnRegionsAndSettings) {
  ArmsSession t;
  t.take_tools();
  ASSERT_NE(t.session.fields("a"), nullptr);
  ASSERT_NE(t.session.fields("b"), nullptr);
  EXPECT_EQ(t.session.fields(""), nullptr);  // the default tool has none
  // Each tool's deformable rows are exactly its arm.
  IndexList rows_a = t.session.model().rows_of(t.a, "a"), rows_b = t.session.model().rows_of(t.b, "b");
  std::sort(rows_a.begin(), rows_a.end());
  std::sort(rows_b.begin(), rows_b.end());
  EXPECT_EQ(t.session.fields("a")->deformable, rows_a);
  EXPECT_EQ(t.session.fields("b")->deformable, rows_b);
  const auto tools = t.session.tools();
  ASSERT_EQ(tools.size(), 2u);
  EXPECT_EQ(tools[0], std::make_pair(std::string("a"), static_cast<Index>(t.a.size())));
  EXPECT_EQ(tools[1], std::make_pair(std::string("b"), static_cast<Index>(t.b.size())));
  // Settings are per tool, history_mb the session's.
  t.session.configure({{"algorithm", std::string("simple")}, {"history_mb", 64.0}}, "a");
  EXPECT_EQ(t.session.settings("a").collision.algorithm, CollisionAlgorithm::Simple);
  EXPECT_EQ(t.session.settings("b").collision.algorithm, CollisionAlgorithm::Robust);
  EXPECT_EQ(t.session.settings("b").history.history_mb, 64.0);
  // A step of one tool moves its arm only.
  const std::uint64_t v = t.session.version();
  t.move("b", -0.05);
  EXPECT_EQ(t.session.changes_since(v).changed, sorted(t.b));
}

TEST(Tool, LocksAreDisjointAndAConflictChangesNothing) {
  ArmsSession t;
  t.session.set_regions({TwoArms::join(t.body, t.b), {}}, {t.a, {}}, "a");
  const std::uint64_t v = t.session.version();
  const std::size_t entries = t.session.history().size();
  // b asks for arm A and arm B as its one region (zero: the body): every surfel of arm A overlaps.
  const std::string msg = expect_error([&] { t.session.set_regions({t.body, {}}, {TwoArms::join(t.a, t.b), {}}, "b"); },
                                       ErrorCode::Conflict, "regions");
  // How many overlap, computed here: rows outside a's zero and outside b's zero.
  std::set<SurfelId> zero_a(t.body.begin(), t.body.end()), zero_b(t.body.begin(), t.body.end());
  zero_a.insert(t.b.begin(), t.b.end());
  std::size_t overlap = 0;
  for (SurfelId id : t.session.model().ids()) overlap += !zero_a.count(id) && !zero_b.count(id);
  EXPECT_EQ(overlap, t.a.size());
  EXPECT_NE(msg.find(std::to_string(overlap) + " surfel"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'a'"), std::string::npos) << msg;
  EXPECT_EQ(t.session.version(), v);
  EXPECT_EQ(t.session.history().size(), entries);
  EXPECT_EQ(t.session.fields("b"), nullptr);
  // One surfel of arm A left out of b's zero region is in b's blend band: it overlaps too.
  const IdList a_but_one(t.a.begin() + 1, t.a.end());
  const std::string one = expect_error([&] { t.session.set_regions({TwoArms::join(t.body, a_but_one), {}}, {t.b, {}}, "b"); },
                                       ErrorCode::Conflict, "regions");
  EXPECT_NE(one.find("1 surfel(s)"), std::string::npos) << one;
  // Disjoint: accepted. The same author may replace its own regions freely.
  t.session.set_regions({TwoArms::join(t.body, t.a), {}}, {t.b, {}}, "b");
  t.session.set_regions({TwoArms::join(t.body, t.b), {}}, {t.a, {}}, "a");
  // Removing or merging surfels another tool's lock holds is refused.
  const IdList some_of_b = {t.b.front()};
  expect_error([&] { t.session.remove(some_of_b, "a"); }, ErrorCode::Conflict, "ids");
}

TEST(Tool, ReleaseFreesTheLockAndUndoTakesItBack) {
  ArmsSession t;
  t.session.set_regions({TwoArms::join(t.body, t.b), {}}, {t.a, {}}, "a");
  t.move("a", 0.02);
  const DeformationFields fields_a = *t.session.fields("a");
  const std::uint64_t v = t.session.version();
  EXPECT_TRUE(t.session.release("a"));
  EXPECT_EQ(t.session.version(), v + 1);
  EXPECT_EQ(t.session.history().back().op, "release");
  EXPECT_EQ(t.session.history().back().author, "a");
  EXPECT_TRUE(t.session.history().back().touched.empty());
  EXPECT_EQ(t.session.fields("a"), nullptr);
  EXPECT_FALSE(t.session.release("a"));  // nothing left to release: no change
  EXPECT_EQ(t.session.version(), v + 1);
  // The lock is free: b may move arm A now.
  t.session.set_regions({t.body, {}}, {TwoArms::join(t.a, t.b), {}}, "b");
  t.session.undo();  // b's set_regions
  t.session.undo();  // a's release: a's regions and lock are back, exactly
  ASSERT_NE(t.session.fields("a"), nullptr);
  EXPECT_EQ(t.session.fields("a")->deformable, fields_a.deformable);
  EXPECT_TRUE(t.session.fields("a")->blend == fields_a.blend);
  expect_error([&] { t.session.set_regions({t.body, {}}, {TwoArms::join(t.a, t.b), {}}, "b"); }, ErrorCode::Conflict,
               "regions");
  // And a can step again.
  EXPECT_GT(t.move("a", 0.02).moved.size(), 0u);
}

TEST(Tool, AnAuthorAloneGetsWhatTheDefaultToolGets) {
  // A session driven by one client id equals one driven in-process (""), bit for bit, undo included.
  SessionFixture x("c1"), y("");
  x.session.set_regions({x.zero, {}}, {x.one, {}}, "c1");
  y.session.set_regions({y.zero, {}}, {y.one, {}});
  for (int k = 0; k < 6; ++k) {
    DeformParams p;
    p.translation = Vec3(0.0, 0.0, -0.05);
    const StepResult rx = x.session.deform(p, "c1");
    const StepResult ry = y.session.deform(p);
    EXPECT_EQ(rx.colliding, ry.colliding);
    EXPECT_EQ(rx.depths, ry.depths);
    expect_same(Snapshot(x.session), Snapshot(y.session), "step " + std::to_string(k));
    EXPECT_EQ(x.session.colliding("c1"), y.session.colliding());
  }
  x.session.undo();
  y.session.undo();
  EXPECT_EQ(x.session.state_hash(), y.session.state_hash());
}

// The two arms swung into each other: tests/core/test_tool_rigid.cpp.

TEST(Tool, UndoAcrossToolsRestoresEveryToolsState) {
  // undo() / redo() in the session's order over two tools: every undo restores the state before its op
  // bit for bit, and each tool steps on afterwards.
  ArmsSession t;
  t.take_tools();
  UndoChecker u;
  for (int k = 0; k < 4; ++k) {
    Snapshot before(t.session);
    t.move(k % 2 ? "a" : "b", k % 2 ? 0.04 : -0.04);
    u.applied(std::move(before));
  }
  while (u.undo(t.session, "undo")) {
  }
  while (u.redo(t.session, "redo")) {
  }
  // A fresh session taking the same ops gives the same next steps (the model; a tool whose entry came
  // back alone re-initialises its detector at its next step, so collision states may differ).
  ArmsSession fresh;
  fresh.take_tools();
  for (int k = 0; k < 4; ++k) fresh.move(k % 2 ? "a" : "b", k % 2 ? 0.04 : -0.04);
  for (const char* tool : {"a", "b", "a"}) {
    t.move(tool, tool[0] == 'a' ? 0.04 : -0.04);
    fresh.move(tool, tool[0] == 'a' ? 0.04 : -0.04);
    EXPECT_EQ(t.session.state_hash(), fresh.session.state_hash());
  }
}

TEST(Tool, ResamplingOfOneToolExtendsTheOthersFields) {
  ArmsSession t;
  t.take_tools();
  t.session.configure({{"resample", true}}, "a");
  DeformParams stretch;
  stretch.translation = Vec3(0, 0, 0.3);  // pulls arm A's top away from the body: its blend band stretches
  t.session.set_regions({TwoArms::join(t.body, t.b), {}}, {IdList(t.a.begin(), t.a.begin() + t.a.size() / 3), {}}, "a");
  const Index before = t.session.model().size();
  t.session.deform(stretch, "a");
  const Index after = t.session.model().size();
  ASSERT_EQ(t.session.fields("b")->regions.size(), static_cast<std::size_t>(after));
  if (after > before) {
    // The new rows are rigid to b (Zero), and b still steps.
    for (Index r = before; r < after; ++r) EXPECT_EQ(t.session.fields("b")->regions[r], Region::Zero);
  }
  EXPECT_GT(t.move("b", -0.02).moved.size(), 0u);
  t.session.undo();
  t.session.undo();
  EXPECT_EQ(t.session.model().size(), before);
  EXPECT_EQ(t.session.fields("b")->regions.size(), static_cast<std::size_t>(before));
}


// The per-deformable-row fields after children are appended and rows removed: every row keeps the lambda
// and gradient it had (checked through the dense views against the rows' old values).
TEST(Tool, ExtendAndCompactKeepEachRowsFields) {
  Points p(40, 3);
  std::vector<Region> regions(40);
  for (int i = 0; i < 40; ++i) {
    p.row(i) << 0.1 * i, 0.05 * (i % 3), 0.0;
    regions[static_cast<std::size_t>(i)] = i < 15 ? Region::Zero : (i < 32 ? Region::Blend : Region::One);
  }
  DeformationFields f = compute_fields(p, regions, 1);
  const Values lam0 = f.lambda();
  const Points grad0 = f.grad_lambda();
  const IndexList parents = {3, 20, 16, 39, 0, 25};  // F0, blend, blend, F1, F0, blend
  extend_fields(f, parents);
  ASSERT_EQ(f.regions.size(), 46u);
  const Values lam1 = f.lambda();
  const Points grad1 = f.grad_lambda();
  EXPECT_TRUE(lam1.head(40) == lam0);
  EXPECT_TRUE(grad1.topRows(40) == grad0);
  for (std::size_t k = 0; k < parents.size(); ++k) {
    const Eigen::Index child = 40 + static_cast<Eigen::Index>(k);
    EXPECT_EQ(f.regions[static_cast<std::size_t>(child)], regions[static_cast<std::size_t>(parents[k])]);
    EXPECT_EQ(lam1[child], lam0[parents[k]]);
    EXPECT_TRUE(grad1.row(child) == grad0.row(parents[k]));
    EXPECT_EQ(f.lambda_of(static_cast<Index>(child)), lam0[parents[k]]);
  }
  EXPECT_TRUE(std::is_sorted(f.deformable.begin(), f.deformable.end()));
  std::vector<bool> keep(46, true);
  for (int r : {0, 16, 17, 31, 39, 41, 45}) keep[static_cast<std::size_t>(r)] = false;
  compact_fields(f, keep);
  const Values lam2 = f.lambda();
  const Points grad2 = f.grad_lambda();
  Eigen::Index j = 0;
  for (Eigen::Index i = 0; i < 46; ++i) {
    if (!keep[static_cast<std::size_t>(i)]) continue;
    EXPECT_EQ(lam2[j], lam1[i]) << "row " << i;
    EXPECT_TRUE(grad2.row(j) == grad1.row(i)) << "row " << i;
    ++j;
  }
  EXPECT_EQ(j, lam2.size());
  EXPECT_EQ(f.blend.rows(), static_cast<Eigen::Index>(f.deformable.size()));
  for (Index r : f.deformable) EXPECT_NE(f.regions[static_cast<std::size_t>(r)], Region::Zero);
}

}  // namespace
}  // namespace surfeledit
