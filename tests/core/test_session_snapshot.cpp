// Session snapshots (EditSession::save / restore, docs/journal.md): a session restored from a snapshot
// into a fresh session is indistinguishable from the one that was saved -- the same state, the same
// history, and the same future. Truth: the saved session itself, which goes on without the snapshot;
// both get the same further ops (steps, per-author undo and redo, configure), and after every op the
// state hash, the whole model bit for bit, every tool's colliding ids, the step results and the history
// lists must agree. Refusals (Conflict) must agree too.
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "expect_error.hpp"
#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/two_arms.hpp"
#include "two_author_script.hpp"

namespace surfeledit {
namespace {

// What an op gave: a step's result, an undo/redo's version, or the error it threw.
struct Outcome {
  std::string error;
  std::uint64_t version = 0;
  IdList colliding;
  std::string response;
  bool operator==(const Outcome& o) const {
    return error == o.error && version == o.version && colliding == o.colliding && response == o.response;
  }
};

using test::ScriptOp;
using Op = ScriptOp;

// Steps, undos and redos (no configure).
std::vector<Op> future_script(std::uint32_t seed, int n) { return test::two_author_script(seed, n, {6, 2, 2, 10}); }

Outcome apply(EditSession& s, const Op& op) {
  Outcome out;
  try {
    if (op.kind == ScriptOp::Step) {
      const StepResult r = s.deform(test::step_params(op), op.author);
      out.colliding = r.colliding;
      out.response = r.response;
      out.version = s.version();
    } else {
      out.version = op.kind == ScriptOp::Undo ? s.undo(op.author) : s.redo(op.author);
    }
  } catch (const Error& e) {
    out.error = std::string(to_string(e.code())) + ": " + e.what();
  }
  return out;
}

void expect_history_equal(const std::vector<HistoryItem>& x, const std::vector<HistoryItem>& y) {
  ASSERT_EQ(x.size(), y.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    EXPECT_EQ(x[k].version, y[k].version);
    EXPECT_EQ(x[k].op, y[k].op);
    EXPECT_EQ(x[k].author, y[k].author);
    EXPECT_EQ(x[k].touched, y[k].touched);
    EXPECT_EQ(x[k].undone, y[k].undone);
  }
}

// Everything a client can observe, compared bit for bit.
void expect_same_state(const EditSession& x, const EditSession& y, const std::string& where) {
  SCOPED_TRACE(where);
  EXPECT_EQ(x.version(), y.version());
  EXPECT_EQ(x.state_hash(), y.state_hash());
  const SurfelArrays& a = x.model().arrays();
  const SurfelArrays& b = y.model().arrays();
  EXPECT_EQ(x.model().ids(), y.model().ids());
  EXPECT_EQ(x.model().next_id(), y.model().next_id());
  EXPECT_TRUE(a.positions == b.positions);
  EXPECT_TRUE(a.normals == b.normals);
  EXPECT_TRUE(a.radii == b.radii);
  EXPECT_TRUE(a.tangent_u == b.tangent_u && a.tangent_v == b.tangent_v);
  EXPECT_TRUE(a.clip_points == b.clip_points && a.clip_dirs == b.clip_dirs);
  EXPECT_EQ(x.tools(), y.tools());
  for (const auto& [author, locked] : x.tools()) EXPECT_EQ(x.colliding(author), y.colliding(author)) << author;
  const Changes cx = x.changes_since(0), cy = y.changes_since(0);
  EXPECT_EQ(cx.changed, cy.changed);
  EXPECT_EQ(cx.removed, cy.removed);
  expect_history_equal(x.history(), y.history());
  // Memory as the report counts it (the history's bound counts alike), but for a tool's step scratch,
  // which is not state (allocated by the tool's next step).
  auto held = [](const EditSession& s) {
    std::vector<StructureInfo> out;
    for (const StructureInfo& i : s.report().structures)
      if (i.name != "step_scratch") out.push_back(i);
    return out;
  };
  const std::vector<StructureInfo> rx = held(x), ry = held(y);
  ASSERT_EQ(rx.size(), ry.size());
  for (std::size_t k = 0; k < rx.size(); ++k) {
    EXPECT_EQ(rx[k].name, ry[k].name);
    EXPECT_EQ(rx[k].bytes, ry[k].bytes) << rx[k].name;
  }
}

struct FutureCase {
  const char* algorithm;
  const char* response;
};

class SnapshotFuture : public ::testing::TestWithParam<FutureCase> {};

// N scripted ops by two authors (undo and redo among them), save, restore into a fresh session, then
// the same M ops on both.
TEST_P(SnapshotFuture, RestoredSessionHasTheSameFuture) {
  const FutureCase c = GetParam();
  TwoArms scene{SampleParams{0.03, 3, 0.25}};
  EditSession live{"live"};
  live.load(scene.model(), "owner");
  for (const char* author : {"a", "b"}) {
    live.configure({{"algorithm", std::string(c.algorithm)}, {"response", std::string(c.response)}}, author);
  }
  live.set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
  live.set_regions({TwoArms::join(scene.body, scene.a), {}}, {scene.b, {}}, "b");
  const std::vector<Op> ops = future_script(13, 40);
  const std::size_t n = 22;
  for (std::size_t k = 0; k < n; ++k) apply(live, ops[k]);
  ASSERT_EQ(live.not_snapshottable(), "");

  SnapshotWriter w;
  live.save(w);
  EditSession copy{"live"};  // the same name: error messages name the session
  SnapshotReader r(w.bytes());
  copy.restore(r);
  expect_same_state(live, copy, "after restore");
  // A second save of the restored session writes the same bytes.
  SnapshotWriter w2;
  copy.save(w2);
  ASSERT_EQ(w.bytes().size(), w2.bytes().size());
  std::size_t first = 0;
  while (first < w.bytes().size() && w.bytes()[first] == w2.bytes()[first]) ++first;
  EXPECT_EQ(first, w.bytes().size()) << "first differing byte";

  int collided = 0;
  for (std::size_t k = n; k < ops.size(); ++k) {
    const Outcome x = apply(live, ops[k]), y = apply(copy, ops[k]);
    EXPECT_TRUE(x == y) << "op " << k << ": " << x.error << " / " << y.error;
    collided += !x.colliding.empty() || (x.response != "none" && !x.response.empty());
    expect_same_state(live, copy, "after op " + std::to_string(k));
    if (::testing::Test::HasFailure()) break;
  }
  // Per-author undo to the bottom of each history, alternating authors.
  for (int k = 0; k < 30; ++k) {
    Op op;
    op.kind = ScriptOp::Undo;
    op.author = k % 2 ? "a" : "b";
    const Outcome x = apply(live, op), y = apply(copy, op);
    EXPECT_TRUE(x == y) << "undo " << k << ": " << x.error << " / " << y.error;
  }
  expect_same_state(live, copy, "after the undos");
  EXPECT_GT(collided, 0) << "the ops after the snapshot must collide, or the detectors' states would not matter";
}

INSTANTIATE_TEST_SUITE_P(
    AlgorithmsAndResponses, SnapshotFuture,
    ::testing::Values(FutureCase{"robust", "report"}, FutureCase{"robust", "cancel"}, FutureCase{"robust", "backoff"},
                    FutureCase{"robust", "merge"}, FutureCase{"temporal", "report"}, FutureCase{"temporal", "cancel"},
                    FutureCase{"temporal", "backoff"}, FutureCase{"temporal", "merge"}, FutureCase{"simple", "report"},
                    FutureCase{"simple", "cancel"}, FutureCase{"simple", "backoff"}, FutureCase{"simple", "merge"}),
    [](const ::testing::TestParamInfo<FutureCase>& info) {
      return std::string(info.param.algorithm) + "_" + info.param.response;
    });

// The scripts above must exercise collisions, or the detectors' states would not matter.
TEST(SessionSnapshot, ScriptCollides) {
  TwoArms scene{SampleParams{0.03, 3, 0.25}};
  EditSession s{"s"};
  s.load(scene.model());
  s.set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
  s.set_regions({TwoArms::join(scene.body, scene.a), {}}, {scene.b, {}}, "b");
  int colliding = 0;
  for (const Op& op : future_script(13, 40)) colliding += !apply(s, op).colliding.empty();
  EXPECT_GT(colliding, 3);
}

// The k-d tree's build is a deterministic function of its points and their order: a tree built again
// (as a restored detector does) answers every query as the first one, ties included (duplicated points).
TEST(SessionSnapshot, KdTreeBuildIsReproducible) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points p(3000, 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i) p.row(i) = Vec3(u(rng), u(rng), u(rng)).transpose();
  for (Eigen::Index i = 0; i < 300; ++i) p.row(2000 + i) = p.row(i);  // exact ties
  IndexList subset;
  for (Index i = 0; i < 3000; i += 3) subset.push_back(i);
  const KdTree a(p), b(p), sa(p, subset), sb(p, subset);
  for (int q = 0; q < 5000; ++q) {
    const Vec3 x = q % 2 ? Vec3(u(rng), u(rng), u(rng)) : Vec3(p.row(q % 3000).transpose());
    double da = 0, db = 0;
    ASSERT_EQ(a.nearest(x, &da), b.nearest(x, &db));
    ASSERT_EQ(da, db);
    ASSERT_EQ(sa.nearest(x, &da), sb.nearest(x, &db));
    ASSERT_EQ(da, db);
  }
}

std::unique_ptr<EditSession> scripted(const char* algorithm) {
  TwoArms scene{SampleParams{0.05, 3, 0.25}};
  auto s = std::make_unique<EditSession>("s");
  s->load(scene.model(), "a");
  s->configure({{"algorithm", std::string(algorithm)}}, "a");
  s->set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
  for (const Op& op : future_script(3, 8)) {
    Op mine = op;
    mine.author = "a";
    apply(*s, mine);
  }
  return s;
}

// Detector kinds without a snapshot make the session not snapshottable (its journal replays the log).
TEST(SessionSnapshot, OtherDetectorsAreNotSnapshottable) {
  auto s = scripted("improved");
  EXPECT_NE(s->not_snapshottable(), "");
  SnapshotWriter w;
  testing_util::expect_error([&] { s->save(w); }, ErrorCode::Internal, "snapshot");
  auto h = scripted("robust");
  ASSERT_EQ(h->not_snapshottable(), "");
  h->configure({{"zero_hierarchy", std::string("aabb")}}, "a");
  EXPECT_NE(h->not_snapshottable(), "");
  auto v = scripted("temporal");
  v->configure({{"inside", std::string("winding")}}, "a");
  EXPECT_NE(v->not_snapshottable(), "");
}

// A corrupt or truncated snapshot is a typed error and changes nothing; never a crash.
TEST(SessionSnapshot, CorruptSnapshotIsATypedErrorAndChangesNothing) {
  auto s = scripted("robust");
  SnapshotWriter w;
  s->save(w);
  const std::string good = w.bytes();
  auto target = scripted("simple");
  const std::uint64_t hash = target->state_hash(), version = target->version();
  const std::size_t items = target->history().size();
  auto expect_refused_or_ok = [&](const std::string& bytes) {
    SnapshotReader r(bytes);
    try {
      EditSession probe{"probe"};
      probe.restore(r);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
      EXPECT_EQ(e.field(), "snapshot");
    }
  };
  // Every truncation is refused.
  for (std::size_t len = 0; len < good.size(); len += 1 + len / 8) {
    SnapshotReader r(good.data(), len);
    testing_util::expect_error([&] { target->restore(r); }, ErrorCode::InvalidArgument, "snapshot");
  }
  EXPECT_EQ(target->state_hash(), hash);
  EXPECT_EQ(target->version(), version);
  EXPECT_EQ(target->history().size(), items);
  // Flipped bytes: refused, or read as some other (well-formed) state; never a crash.
  std::mt19937 rng(11);
  for (int k = 0; k < 300; ++k) {
    std::string bad = good;
    bad[rng() % bad.size()] ^= static_cast<char>(1u << (rng() % 8));
    expect_refused_or_ok(bad);
  }
  // An unknown format version names itself.
  std::string future = good;
  future[4] = 9;
  SnapshotReader r(future);
  try {
    target->restore(r);
    ADD_FAILURE() << "an unknown format was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("format version 9"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace surfeledit
