// Undo and redo behind every detector (issue 9 §1): hierarchies (zero trees of every kind, a deformable
// tree with every refit mode, the extended narrow phase) and approximate detection on clusters. After
// random sequences of steps, removals, undos and redos, the session must equal a fresh session that
// replayed only the ops still applied -- its model bit for bit, its colliding set, and the colliding ids
// and depths of a probe step taken by both (so the detector's hidden state came back too).
#include <gtest/gtest.h>

#include <random>
#include <variant>

#include "session_fixture.hpp"
#include "surfeledit/core/edit_session.hpp"

namespace surfeledit {
namespace {

using Config = std::vector<NamedSetting>;

struct Named {
  std::string name;
  Config config;
};

void PrintTo(const Named& n, std::ostream* os) { *os << n.name; }

std::vector<Named> configs() {
  auto s = [](const char* v) { return std::string(v); };
  return {
      {"robust_plain", {}},
      {"robust_aabb", {{"zero_hierarchy", s("aabb")}}},
      {"simple_obb", {{"algorithm", s("simple")}, {"zero_hierarchy", s("obb")}}},
      {"temporal_sphere", {{"algorithm", s("temporal")}, {"zero_hierarchy", s("sphere")}}},
      {"robust_sphere_hierarchical", {{"zero_hierarchy", s("sphere_hierarchical")}}},
      {"robust_tree_tree_bottom_up",
       {{"zero_hierarchy", s("aabb")}, {"deformable_hierarchy", s("aabb")}, {"update", s("bottom_up")}}},
      {"robust_tree_tree_top_down",
       {{"zero_hierarchy", s("obb")}, {"deformable_hierarchy", s("aabb")}, {"update", s("top_down")}}},
      {"simple_tree_tree_hybrid",
       {{"algorithm", s("simple")}, {"zero_hierarchy", s("aabb")}, {"deformable_hierarchy", s("aabb")},
        {"update", s("hybrid")}}},
      {"robust_extended", {{"zero_hierarchy", s("aabb")}, {"deformable_hierarchy", s("aabb")}, {"extended", true}}},
      {"robust_simplified", {{"simplify", s("hierarchical")}, {"cluster_size", 8}}},
      {"temporal_simplified", {{"algorithm", s("temporal")}, {"simplify", s("region_growing")}, {"cluster_size", 6}}},
      {"robust_aabb_backoff", {{"zero_hierarchy", s("aabb")}, {"response", s("backoff")}}},
      {"simple_simplified_cancel", {{"algorithm", s("simple")}, {"simplify", s("hierarchical")}, {"response", s("cancel")}}},
  };
}

using DetectorOp = std::variant<DeformParams, IdList>;  // a step, or a removal

struct DetectorScene : SessionFixture {
  explicit DetectorScene(const Config& config) {
    session.set_regions({zero, {}}, {one, {}});
    session.configure(config);
  }
};

void apply_op(EditSession& s, const DetectorOp& op) {
  if (const auto* p = std::get_if<DeformParams>(&op)) s.deform(*p);
  else s.remove(std::get<IdList>(op));
}

// A probe step (down with a slight rotation) taken by both sessions: the same results, bit for bit;
// then undone in `a`. True when the probe collided.
bool expect_same_future(EditSession& a, EditSession& b, const std::string& where) {
  SCOPED_TRACE(where);
  DeformParams p;
  p.translation = Vec3(0.01, 0, -0.07);
  p.angle = 0.05;
  p.axis = Vec3(1, 0, 0);
  const StepResult ra = a.deform(p), rb = b.deform(p);
  EXPECT_EQ(ra.colliding, rb.colliding);
  EXPECT_EQ(ra.depths, rb.depths);
  EXPECT_EQ(ra.response, rb.response);
  expect_same(Snapshot(a), Snapshot(b), "after the probe");
  if (ra.response != "cancelled") a.undo();  // back to where the sequence was (itself checked below)
  return !ra.colliding.empty();
}

class HistoryDetectors : public ::testing::TestWithParam<Named> {};

TEST_P(HistoryDetectors, UndoEqualsAFreshReplayOfTheKeptOps) {
  const Config& config = GetParam().config;
  DetectorScene a(config);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<DetectorOp> applied, undone;
  int checks = 0, colliding_checks = 0, probes = 0;
  for (int it = 0; it < 22; ++it) {
    const unsigned what = rng() % 10;
    if (what < 5) {
      DeformParams p;
      p.translation = Vec3(0.02 * (u(rng) - 0.5), 0, -(0.04 + 0.06 * u(rng)));
      p.angle = 0.15 * (u(rng) - 0.5);
      p.axis = Vec3(1, 0, 0);
      if (a.session.deform(p).response == "cancelled") continue;  // no entry: nothing to replay
      applied.emplace_back(p);
      undone.clear();
    } else if (what < 6) {
      const IdList& ids = a.session.model().ids();
      const SurfelId id = ids[rng() % ids.size()];
      if (id == a.zero.front() || id == a.one.front()) continue;  // keep both regions non-empty
      a.session.remove({id});
      applied.emplace_back(IdList{id});
      undone.clear();
    } else if (what < 9 && !applied.empty()) {
      a.session.undo();
      undone.push_back(applied.back());
      applied.pop_back();
    } else if (!undone.empty()) {
      a.session.redo();
      applied.push_back(undone.back());
      undone.pop_back();
    } else {
      continue;
    }
    DetectorScene b(config);
    for (const DetectorOp& op : applied) apply_op(b.session, op);
    const std::string where = GetParam().name + " op " + std::to_string(it);
    expect_same(Snapshot(a.session), Snapshot(b.session), where);
    // Every other check (at random) also compares a probe step; it drops A's redo tail.
    if (rng() % 2 == 0 || undone.empty()) {
      const Snapshot now(a.session);
      colliding_checks += expect_same_future(a.session, b.session, where);
      expect_same(Snapshot(a.session), now, where + ": probe undone");
      undone.clear();
      ++probes;
    }
    ++checks;
  }
  EXPECT_GE(checks, 10);
  EXPECT_GE(probes, 5);
  EXPECT_GE(colliding_checks, 2);  // probes from states close enough to collide
}

INSTANTIATE_TEST_SUITE_P(All, HistoryDetectors, ::testing::ValuesIn(configs()),
                         [](const ::testing::TestParamInfo<Named>& info) { return info.param.name; });

}  // namespace
}  // namespace surfeledit
