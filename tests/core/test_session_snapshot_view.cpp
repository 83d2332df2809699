// Snapshot views (EditSession::snapshot_view, session_snapshot_view.hpp): a view taken at one point and
// encoded after the session went on -- steps, per-author undo and redo, configure, entries dropped by a
// small history bound, spare buffers reused, the session closed -- writes exactly the bytes a synchronous
// save wrote at that point. Truth: that save's bytes, and a twin session given the same ops without a view,
// whose every observable (state hash, history lists, the report's memory counts, which the history's
// bound reads) must agree with the session that holds the view. Restoring the view's bytes gives the
// state at the point (version, state hash, history).
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <thread>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/two_arms.hpp"
#include "two_author_script.hpp"

namespace surfeledit {
namespace {

using test::ScriptOp;
using Op = ScriptOp;

// Steps, undos, redos and configures (tool-only images).
std::vector<Op> view_script(std::uint32_t seed, int n) { return test::two_author_script(seed, n, {7, 2, 2, 12}); }

// The op's outcome as text (a step's colliding count and response, a version, or the error).
std::string apply(EditSession& s, const Op& op, int k) {
  try {
    if (op.kind == ScriptOp::Step) {
      const StepResult r = s.deform(test::step_params(op), op.author);
      return "step " + std::to_string(r.colliding.size()) + " " + r.response;
    }
    if (op.kind == ScriptOp::Configure) {
      s.configure({{"parallel_min_ms", 1.0 + k}}, op.author);
      return "configure";
    }
    return std::to_string(op.kind == ScriptOp::Undo ? s.undo(op.author) : s.redo(op.author));
  } catch (const Error& e) {
    return std::string("error ") + e.what();
  }
}

// What the two sessions show: version, state hash, history list, and the report's memory counts (but for
// a tool's step scratch, and with `restored` its rigid rows held while it is not stale with known rows:
// neither is state, a snapshot keeps neither).
std::string observe(const EditSession& s, bool restored = false) {
  std::string out = std::to_string(s.version()) + " " + std::to_string(s.state_hash()) + "\n";
  for (const HistoryItem& h : s.history()) {
    out += std::to_string(h.version) + " " + h.op + " " + h.author + " " + std::to_string(h.touched.size()) +
           (h.undone ? " undone\n" : "\n");
  }
  const SessionReport rep = s.report();
  for (const StructureInfo& i : rep.structures)
    if (i.name != "step_scratch" && !(restored && i.name == "rigid_held")) out += i.name + " " + std::to_string(i.bytes) + "\n";
  for (const SessionReport::HistoryKind& k : rep.history_kinds)
    out += k.kind + " " + std::to_string(k.entries) + " " + std::to_string(k.bytes) + "\n";
  return out;
}

struct ViewCase {
  const char* algorithm;
  const char* response;
};

void prepare(EditSession& s, const TwoArms& scene, const ViewCase& c, double history_mb) {
  s.load(scene.model(), "owner");
  for (const char* author : {"a", "b"}) {
    s.configure({{"algorithm", std::string(c.algorithm)}, {"response", std::string(c.response)},
                 {"history_mb", history_mb}},
                author);
  }
  s.set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
  s.set_regions({TwoArms::join(scene.body, scene.a), {}}, {scene.b, {}}, "b");
}

std::size_t first_difference(const std::string& x, const std::string& y) {
  std::size_t k = 0;
  while (k < x.size() && k < y.size() && x[k] == y[k]) ++k;
  return k;
}

class SnapshotView : public ::testing::TestWithParam<ViewCase> {};

// The view outlives the point by many ops (entries dropped and replaced, spares reused) and is encoded
// on another thread while the session goes on; then the session is closed before a second encode.
TEST_P(SnapshotView, EncodesThePointWhileTheSessionGoesOn) {
  const ViewCase c = GetParam();
  const TwoArms scene{SampleParams{0.03, 3, 0.25}};
  // A bound small enough that entries are dropped after the point (checked below).
  const double history_mb = 0.5;
  auto live = std::make_unique<EditSession>("live");
  EditSession twin{"live"};
  prepare(*live, scene, c, history_mb);
  prepare(twin, scene, c, history_mb);
  const std::vector<Op> ops = view_script(29, 90);
  const std::size_t point = 45;
  for (std::size_t k = 0; k < point; ++k) ASSERT_EQ(apply(*live, ops[k], int(k)), apply(twin, ops[k], int(k)));
  ASSERT_EQ(live->not_snapshottable(), "");

  SnapshotWriter sync;
  live->save(sync);
  const std::string at_point = observe(*live, true);
  const std::vector<HistoryItem> items_at_point = live->history();
  SessionSnapshotView view = live->snapshot_view();
  EXPECT_GT(view.shared_images(), 0u);

  std::string threaded;
  std::thread encoder([&] {
    SnapshotWriter w;
    view.encode(w);
    threaded = w.take();
  });
  std::size_t dropped = 0;
  for (std::size_t k = point; k < ops.size(); ++k) {
    const std::size_t before = live->history().size();
    const std::string x = apply(*live, ops[k], int(k)), y = apply(twin, ops[k], int(k));
    EXPECT_EQ(x, y) << "op " << k;
    dropped += live->history().size() <= before && ops[k].kind != 1 && ops[k].kind != 2;
    EXPECT_EQ(observe(*live), observe(twin)) << "op " << k;
    if (::testing::Test::HasFailure()) break;
  }
  encoder.join();
  EXPECT_GT(dropped, 5u) << "the bound must drop entries after the point";

  EXPECT_EQ(first_difference(threaded, sync.bytes()), sync.bytes().size());
  EXPECT_EQ(threaded.size(), sync.bytes().size());
  live.reset();  // closed: the view holds what it encodes
  SnapshotWriter after_close;
  view.encode(after_close);
  EXPECT_TRUE(after_close.bytes() == sync.bytes());

  EditSession restored{"live"};
  SnapshotReader r(after_close.bytes());
  restored.restore(r);
  EXPECT_EQ(observe(restored, true), at_point);
  ASSERT_EQ(restored.history().size(), items_at_point.size());
  for (std::size_t k = 0; k < items_at_point.size(); ++k) EXPECT_EQ(restored.history()[k].touched, items_at_point[k].touched);
}

INSTANTIATE_TEST_SUITE_P(AlgorithmsAndResponses, SnapshotView,
                         ::testing::Values(ViewCase{"none", "report"}, ViewCase{"robust", "merge"},
                                         ViewCase{"robust", "cancel"}, ViewCase{"temporal", "backoff"},
                                         ViewCase{"temporal", "merge"}, ViewCase{"simple", "report"}),
                         [](const ::testing::TestParamInfo<ViewCase>& info) {
                           return std::string(info.param.algorithm) + "_" + info.param.response;
                         });

}  // namespace
}  // namespace surfeledit
