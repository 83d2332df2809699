// The step journal of a bounded deformable tree (bvh_journal-inl.hpp): the undo image of a few steps as the
// nodes they changed. Truth: a copy of the tree taken before the journal started (what the undo image used to
// be). After restore() the two agree on every node's box, its bound in the current step and whether it was fit
// in it, and the same later steps give both the same candidates and boxes, bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "bvh_test_util.hpp"
#include "surfeledit/core/bvh/traversal.hpp"
#include "surfeledit/core/types.hpp"

namespace {

using namespace bvh_test;

bool bits_equal(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
bool same_box(const Aabb& a, const Aabb& b) {
  for (int d = 0; d < 3; ++d)
    if (!bits_equal(a.lo[d], b.lo[d]) || !bits_equal(a.hi[d], b.hi[d])) return false;
  return true;
}

// Every node's box, bound and fitted flag, and the step and shift, alike bit for bit.
::testing::AssertionResult same_tree(const Bvh<Aabb>& a, const Bvh<Aabb>& b) {
  if (a.nodes().size() != b.nodes().size()) return ::testing::AssertionFailure() << "node counts differ";
  if (a.step() != b.step() || !bits_equal(a.shift(), b.shift()))
    return ::testing::AssertionFailure() << "step " << a.step() << " / " << b.step() << ", shift " << a.shift()
                                         << " / " << b.shift();
  for (std::int32_t k = 0; k < static_cast<std::int32_t>(a.nodes().size()); ++k) {
    if (!same_box(a.box(k), b.box(k))) return ::testing::AssertionFailure() << "node " << k << ": boxes differ";
    if (a.fitted(k) != b.fitted(k)) return ::testing::AssertionFailure() << "node " << k << ": fitted differs";
    if (!same_box(a.bound(k), b.bound(k))) return ::testing::AssertionFailure() << "node " << k << ": bounds differ";
  }
  return ::testing::AssertionSuccess();
}

// A deformable sheet above a zero sheet; step k moves it by a fixed function of k (so a replay moves it alike).
struct JournalSheets {
  Points p, previous;
  Values r;
  IndexList zero, def;
  Bvh<Aabb> zero_tree;

  JournalSheets() {
    Points pz, pd;
    Values rz, rd;
    make_sheet(2500, 61, pz, rz);
    make_sheet(1500, 62, pd, rd, 0.35, 0.6);
    p.resize(pz.rows() + pd.rows(), 3);
    p << pz, pd;
    r.resize(p.rows());
    r << rz, rd;
    for (Index i = 0; i < pz.rows(); ++i) zero.push_back(i);
    for (Index i = pz.rows(); i < p.rows(); ++i) def.push_back(i);
    zero_tree = Bvh<Aabb>(p, r, zero);
  }
  BvhParams bounded() const {
    BvhParams params;
    params.update = UpdateMode::Bounded;
    return params;
  }
  // Moves the deformable rows for step k (down for the first steps, then a small jitter), then one bounded step
  // of `tree` and a tree/tree traversal; returns the candidate rows, sorted.
  IndexList step(Bvh<Aabb>& tree, int k) {
    previous = p;
    double reach = 0.0;
    for (Index d : def) {
      if (k < 6) p(d, 2) -= 0.05;
      p(d, 0) += (k % 2 ? 1e-4 : -1e-4) * (1.0 + 0.1 * std::sin(double(d)));
      reach = std::max(reach, (p.row(d) - previous.row(d)).norm());
    }
    reach *= 1.0 + 1e-12;
    tree.step_bounded(p, previous, r, reach * (1.0 + 1e-12), reach);
    CollectRows narrow;
    BvhCounters c;
    collide(zero_tree, tree, SatMode::Lite, narrow, c);
    std::sort(narrow.rows.begin(), narrow.rows.end());
    return narrow.rows;
  }
  // A bounded tree over the deformable rows after steps 0 .. steps-1.
  Bvh<Aabb> tree_after(int steps) {
    Bvh<Aabb> tree(p, r, def, bounded());
    for (int k = 0; k < steps; ++k) step(tree, k);
    return tree;
  }
};

// The sheets, a tree after `steps` steps with a journal started, and (the truth) a copy of the tree and the
// positions as they were at the start.
struct Journaled {
  JournalSheets s;
  Bvh<Aabb> tree;
  const Bvh<Aabb> start;
  const Points p0;
  explicit Journaled(int steps) : tree(s.tree_after(steps)), start(tree), p0(s.p) {
    EXPECT_TRUE(tree.start_journal());
  }
};

TEST(BvhJournal, RestoredStepsLeaveTheTreeAsACopyTakenBefore) {
  Journaled j(3);
  JournalSheets& s = j.s;
  Bvh<Aabb>& tree = j.tree;
  const Bvh<Aabb>& copy = j.start;
  const Points& p0 = j.p0;
  IndexList last;
  for (int k = 3; k < 8; ++k) {
    if (k == 5) tree.refit_all_next_step();  // as after adopting a rebuilt tree: every node fit in one step
    last = s.step(tree, k);
  }
  EXPECT_FALSE(last.empty()) << "the sheets should touch by now";
  const Bvh<Aabb>::StepImage image = tree.journal();
  EXPECT_EQ(image.step_after, tree.step());
  tree.stop_journal();
  ASSERT_TRUE(tree.fits(image));
  tree.restore(image);
  EXPECT_TRUE(same_tree(tree, copy));
  // The same later steps from the same positions: the same candidates and trees.
  Bvh<Aabb> twin = copy;
  Points from = p0;
  for (int k = 3; k < 9; ++k) {
    s.p = from;
    const IndexList a = s.step(tree, k);
    s.p = from;
    const IndexList b = s.step(twin, k);
    from = s.p;
    EXPECT_EQ(a, b) << "step " << k;
    EXPECT_TRUE(same_tree(tree, twin)) << "step " << k;
  }
}

// One step's journal holds exactly the nodes the step fit or narrowed (those fitted in it), each once, with the
// box it had before; for a step near first contact that is part of the tree.
TEST(BvhJournal, AStepKeepsExactlyTheNodesItChanged) {
  Journaled j(2);
  Bvh<Aabb>& tree = j.tree;
  const Bvh<Aabb>& copy = j.start;
  j.s.step(tree, 8);
  const Bvh<Aabb>::StepImage image = tree.journal();
  std::vector<int> seen(tree.nodes().size(), 0);
  for (const auto& e : image.saved) {
    ++seen[static_cast<std::size_t>(e.node)];
    EXPECT_TRUE(same_box(e.box, copy.box(e.node))) << "node " << e.node;
  }
  std::size_t fitted = 0;
  for (std::int32_t k = 0; k < static_cast<std::int32_t>(tree.nodes().size()); ++k) {
    fitted += tree.fitted(k);
    EXPECT_EQ(seen[static_cast<std::size_t>(k)], tree.fitted(k) ? 1 : 0) << "node " << k;
  }
  EXPECT_GT(fitted, 0u);
  EXPECT_LT(fitted, tree.nodes().size());
}

// A back-off takes the step back within the journal (restore_journal) and steps again: the image then still
// leads back to the start.
TEST(BvhJournal, StepsTakenBackWithinTheJournalStillLeadBackToItsStart) {
  Journaled j(4);
  j.s.step(j.tree, 4);
  j.s.step(j.tree, 5);
  j.tree.restore_journal();
  EXPECT_TRUE(same_tree(j.tree, j.start));
  j.s.p = j.p0;
  j.s.step(j.tree, 4);
  const Bvh<Aabb>::StepImage image = j.tree.journal();
  j.tree.restore(image);
  EXPECT_TRUE(same_tree(j.tree, j.start));
}

// A copy taken within the journal takes it along: assigned back after more steps (a back-off's image of a few
// rows), the journal still leads back to its start.
TEST(BvhJournal, ACopyTakenWithinTheJournalAssignedBackKeepsItsStart) {
  Journaled j(3);
  j.s.step(j.tree, 3);
  const Bvh<Aabb> midway = j.tree;
  EXPECT_TRUE(midway.journaling());
  j.s.step(j.tree, 4);
  j.s.step(j.tree, 5);
  j.tree = midway;
  EXPECT_TRUE(same_tree(j.tree, midway));
  j.tree.restore_journal();
  EXPECT_TRUE(same_tree(j.tree, j.start));
}

// An image of another step, or of another tree, is refused and changes nothing.
TEST(BvhJournal, AnImageThatDoesNotFitIsRefused) {
  Journaled j(4);
  JournalSheets& s = j.s;
  Bvh<Aabb>& tree = j.tree;
  s.step(tree, 4);
  const Bvh<Aabb>::StepImage image = tree.journal();
  tree.stop_journal();
  s.step(tree, 5);  // a step the image does not cover
  const Bvh<Aabb> before = tree;
  EXPECT_FALSE(tree.fits(image));
  try {
    tree.restore(image);
    ADD_FAILURE() << "restore of a stale image did not throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Internal);
  }
  EXPECT_TRUE(same_tree(tree, before));
  Bvh<Aabb> other(s.p, s.r, IndexList(s.def.begin(), s.def.begin() + 200), s.bounded());
  EXPECT_FALSE(other.fits(image));
}

// No journal where a step may change more than boxes: a tree with dead slots (compaction moves rows), a tree
// refit by another update mode, other box kinds. Insertions end a journal; refit() of a journaled tree throws.
TEST(BvhJournal, OnlyBoundedAabbTreesWithoutDeadSlotsKeepOne) {
  JournalSheets s;
  Bvh<Aabb> tree(s.p, s.r, s.def, s.bounded());
  ASSERT_TRUE(tree.start_journal());
  EXPECT_TRUE(tree.journaling());
  EXPECT_THROW(tree.refit(s.p, s.r), Error);
  const IndexList parents = {s.def[0]};
  Points grown(s.p.rows() + 1, 3);
  grown << s.p, s.p.row(s.def[0]);
  Values radii(s.r.size() + 1);
  radii << s.r, s.r[s.def[0]];
  tree.on_inserted(grown, radii, parents);
  EXPECT_FALSE(tree.journaling());
  std::vector<bool> keep(static_cast<std::size_t>(grown.rows()), true);
  keep[static_cast<std::size_t>(s.def[1])] = false;
  tree.on_removed(keep);
  EXPECT_FALSE(tree.start_journal());
  for (UpdateMode mode : {UpdateMode::BottomUp, UpdateMode::TopDown, UpdateMode::Hybrid}) {
    BvhParams params;
    params.update = mode;
    Bvh<Aabb> other(s.p, s.r, s.def, params);
    EXPECT_FALSE(other.start_journal()) << to_string(mode);
  }
  Bvh<Obb> obb(s.p, s.r, s.def, s.bounded());
  EXPECT_FALSE(obb.start_journal());
}

}  // namespace
