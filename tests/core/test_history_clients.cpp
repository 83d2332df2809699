// Per-client undo and redo (issue 11 §3): an author undoes its own last change, bit for bit on the
// surfels it touched, and is refused exactly when another author's later change touched one of them.
// Truth: snapshots taken before each op, and the refusal computed here from history() alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "expect_error.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/two_arms.hpp"

namespace surfeledit {
namespace {

using testing_util::expect_error;

// The two-arm scene (core/two_arms.hpp), coarser than test_tool.cpp's: part 0 body, 1 arm A, 2 arm B.
struct Arms {
  TwoArms scene{SampleParams{0.03, 3, 0.25}};
  EditSession session{"clients"};
  const IdList& body = scene.body;
  const IdList& a = scene.a;
  const IdList& b = scene.b;
  Arms() { session.load(scene.model(), "owner"); }
  static IdList join(IdList x, const IdList& y) { return TwoArms::join(std::move(x), y); }
  void take(const std::string& tool, const IdList& arm, const IdList& other_arm) {
    session.set_regions({join(body, other_arm), {}}, {arm, {}}, tool);
  }
  void move(const std::string& tool, const Vec3& t) {
    DeformParams p;
    p.translation = t;
    session.deform(p, tool);
  }
  // Positions and normals of `ids`, copied.
  std::pair<Points, Points> rows(const IdList& ids) const {
    const SurfelModel& m = session.model();
    Points p(static_cast<Eigen::Index>(ids.size()), 3), n(p.rows(), 3);
    for (std::size_t k = 0; k < ids.size(); ++k) {
      p.row(static_cast<Eigen::Index>(k)) = m.positions().row(m.row_of(ids[k]));
      n.row(static_cast<Eigen::Index>(k)) = m.normals().row(m.row_of(ids[k]));
    }
    return {p, n};
  }
};

void expect_rows(const std::pair<Points, Points>& x, const std::pair<Points, Points>& y, const std::string& where) {
  SCOPED_TRACE(where);
  EXPECT_TRUE(x.first == y.first);  // bitwise
  EXPECT_TRUE(x.second == y.second);
}

// What undo(author) must refuse, from history() alone: the author's last applied entry and the first
// later entry (applied or undone after it) of another author touching one of its surfels.
const HistoryItem* expected_refusal(const std::vector<HistoryItem>& h, const std::string& author) {
  int target = -1;
  for (int k = static_cast<int>(h.size()) - 1; k >= 0 && target < 0; --k)
    if (!h[k].undone && h[k].author == author) target = k;
  if (target < 0) return nullptr;
  const std::set<SurfelId> mine(h[target].touched.begin(), h[target].touched.end());
  for (std::size_t k = static_cast<std::size_t>(target) + 1; k < h.size(); ++k) {
    if (h[k].author == author) continue;
    for (SurfelId id : h[k].touched)
      if (mine.count(id)) return &h[k];
  }
  return nullptr;
}

TEST(HistoryClients, EachUndoesItsOwnStepAndLeavesTheOthersExact) {
  Arms s;
  s.take("a", s.a, s.b);
  s.take("b", s.b, s.a);
  const auto a0 = s.rows(s.a), b0 = s.rows(s.b);
  s.move("a", Vec3(0.03, 0, 0));
  const auto a1 = s.rows(s.a);
  s.move("b", Vec3(-0.03, 0, 0));
  const auto b1 = s.rows(s.b);
  s.move("a", Vec3(0.03, 0, 0.01));
  const auto a2 = s.rows(s.a);
  const std::uint64_t hash2 = s.session.state_hash();
  // b's step is older than a's last one, but touched other surfels: b may undo it.
  ASSERT_EQ(expected_refusal(s.session.history(), "b"), nullptr);
  const std::uint64_t v = s.session.version();
  EXPECT_EQ(s.session.undo("b"), v + 1);
  expect_rows(s.rows(s.b), b0, "b undone");
  expect_rows(s.rows(s.a), a2, "a untouched by b's undo");
  const std::vector<HistoryItem> h = s.session.history();
  EXPECT_TRUE(std::find_if(h.begin(), h.end(), [](const HistoryItem& i) { return i.author == "b" && i.op == "deform"; })->undone);
  // a undoes its own two steps, b's undo notwithstanding.
  s.session.undo("a");
  expect_rows(s.rows(s.a), a1, "a's last step undone");
  s.session.undo("a");
  expect_rows(s.rows(s.a), a0, "a's first step undone");
  // Redo each in turn: back to the state after all three steps, bit for bit.
  s.session.redo("b");
  expect_rows(s.rows(s.b), b1, "b redone");
  s.session.redo("a");
  s.session.redo("a");
  expect_rows(s.rows(s.a), a2, "a redone");
  EXPECT_EQ(s.session.state_hash(), hash2);
  // Nothing of a client left: Conflict naming the history.
  expect_error([&] { s.session.redo("a"); }, ErrorCode::Conflict, "history");
  expect_error([&] { s.session.undo("nobody"); }, ErrorCode::Conflict, "history");
  // Both tools step on after the out-of-order undo and redo.
  s.move("a", Vec3(0.01, 0, 0));
  s.move("b", Vec3(-0.01, 0, 0));
}

TEST(HistoryClients, RefusedExactlyWhenAnotherClientsLaterOpTouchedItsSurfels) {
  Arms s;
  s.take("a", s.a, s.b);
  s.move("a", Vec3(0, 0, 0.02));  // a's step over arm A
  s.session.release("a");
  s.take("b", s.a, s.b);  // b takes arm A over and moves it
  s.move("b", Vec3(0, 0, 0.02));
  const std::uint64_t b_step = s.session.version();
  s.session.release("b");
  s.take("a", s.a, s.b);
  // a's last entries (set_regions, release) touched no surfel: undone, its tool comes back each time.
  for (int k = 0; k < 2; ++k) {
    ASSERT_EQ(expected_refusal(s.session.history(), "a"), nullptr) << k;
    s.session.undo("a");
  }
  ASSERT_NE(s.session.fields("a"), nullptr);  // the release undone: a holds arm A again
  // a's step: b's later step touched the same surfels -- refused, naming it; nothing changes.
  const std::vector<HistoryItem> history = s.session.history();  // kept: `hit` points into it
  const HistoryItem* hit = expected_refusal(history, "a");
  ASSERT_NE(hit, nullptr);
  EXPECT_EQ(hit->version, b_step);
  const auto before = s.rows(s.a);
  const std::uint64_t v = s.session.version(), hash = s.session.state_hash();
  const std::size_t undone = [&] {
    std::size_t n = 0;
    for (const HistoryItem& i : s.session.history()) n += i.undone;
    return n;
  }();
  const std::string msg = expect_error([&] { s.session.undo("a"); }, ErrorCode::Conflict, "history");
  EXPECT_NE(msg.find("client 'b'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("(version " + std::to_string(b_step) + ")"), std::string::npos) << msg;
  EXPECT_EQ(s.session.version(), v);
  EXPECT_EQ(s.session.state_hash(), hash);
  expect_rows(s.rows(s.a), before, "refused");
  std::size_t undone_after = 0;
  for (const HistoryItem& i : s.session.history()) undone_after += i.undone;
  EXPECT_EQ(undone_after, undone);
  // b's release cannot be undone either while a holds arm A (b's regions would overlap a's lock).
  expect_error([&] { s.session.undo("b"); }, ErrorCode::Conflict, "history");
}

TEST(HistoryClients, AnOpThatRenumberedRowsCannotBeUndoneAlone) {
  Arms s;
  s.take("a", s.a, s.b);
  s.take("b", s.b, s.a);
  s.move("a", Vec3(0.02, 0, 0));
  const IdList some_body = {s.body.front(), s.body.back()};
  s.session.remove(some_body, "b");  // renumbers the rows
  // a's step touched other surfels, but its rows were renumbered since: refused, naming b's remove.
  const std::string msg = expect_error([&] { s.session.undo("a"); }, ErrorCode::Conflict, "history");
  EXPECT_NE(msg.find("'remove'"), std::string::npos) << msg;
  // b may undo its remove (nothing of another client came after it), then a its step.
  s.session.undo("b");
  EXPECT_GE(s.session.model().row_of(some_body.front()), 0);
  s.session.undo("a");
}

}  // namespace
}  // namespace surfeledit
