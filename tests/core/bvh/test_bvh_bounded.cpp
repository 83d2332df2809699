// The bounded update of a deformable AABB tree (bvh_bounded-inl.hpp): its boxes are last fits grown by
// the steps' displacements, leaves refit only where a traversal reaches them. Its candidates are checked
// against brute force on every step of a drag with idle jitter, large moves, per-row noise, growing
// radii, insertions and removals: every deformable row whose ball (p, r + |t|) overlaps a zero ball
// must be a candidate (a lazy box that missed one would fail here), each once per step.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "bvh_test_util.hpp"
#include "surfeledit/core/bvh/overlap.hpp"
#include "surfeledit/core/bvh/traversal.hpp"

namespace {

using namespace bvh_test;

struct Drag {
  Points p, previous;
  Values r, r_before;
  IndexList zero, def;
  std::mt19937_64 rng{2026};

  Drag(int nz, int nd, double z_def) {
    Points pz, pd;
    Values rz, rd;
    make_sheet(nz, 41, pz, rz);
    make_sheet(nd, 42, pd, rd, z_def, 0.5);
    p.resize(nz + nd, 3);
    p << pz, pd;
    r.resize(nz + nd);
    r << rz, rd;
    for (int i = 0; i < nz; ++i) zero.push_back(i);
    for (int i = 0; i < nd; ++i) def.push_back(nz + i);
  }
  double t_of(Index d) const { return (p.row(d) - previous.row(d)).norm(); }
  // Deformable rows whose ball of this step overlaps some zero ball (brute force, exact distances).
  std::set<Index> brute() const {
    std::set<Index> out;
    for (Index d : def)
      for (Index z : zero)
        if ((p.row(d) - p.row(z)).norm() <= r[d] + t_of(d) + r[z]) {
          out.insert(d);
          break;
        }
    return out;
  }
  // The step's shift and reach as the detector defines them, computed here independently.
  std::pair<double, double> shift_reach() const {
    double reach = 0.0, grow = 0.0;
    for (Index d : def) {
      reach = std::max(reach, t_of(d));
      if (d < r_before.size()) grow = std::max(grow, r[d] - r_before[d]);
    }
    reach *= 1.0 + 1e-12;
    return {(reach + grow) * (1.0 + 1e-12), reach};
  }
};

TEST(BvhBounded, CandidatesContainEveryOverlapEveryStep) {
  Drag s(3000, 1200, 0.45);
  BvhParams zp;
  Bvh<Aabb> zero(s.p, s.r, s.zero, zp);
  BvhParams dp;
  dp.update = UpdateMode::Bounded;
  Bvh<Aabb> def(s.p, s.r, s.def, dp);
  ASSERT_TRUE(def.bounded());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::size_t total_truth = 0, idle_refits = 0, leaves = 0;
  for (const auto& nd : def.nodes()) leaves += nd.leaf();
  for (int step = 0; step < 60; ++step) {
    s.previous = s.p;
    s.r_before = s.r;
    const int kind = step % 6;
    for (Index d : s.def) {
      if (kind == 0 || kind == 3) {  // a drag down and sideways
        s.p(d, 2) -= 0.03;
        s.p(d, 0) += 0.01 * std::sin(3.0 * s.p(d, 1) + step);
      } else if (kind == 1) {  // idle jitter, alternating sign
        s.p(d, 0) += (step % 2 ? 1e-4 : -1e-4);
      } else if (kind == 2) {  // independent noise per row
        for (int a = 0; a < 3; ++a) s.p(d, a) += 0.004 * u(s.rng);
      } else if (kind == 4) {  // a few radii grow, nothing moves
        if (u(s.rng) > 0.9) s.r[d] *= 1.5;
      } else {  // back up a little
        s.p(d, 2) += 0.01;
      }
    }
    if (step == 20 || step == 41) {  // insertions: children beside random deformable parents
      const Index old = static_cast<Index>(s.p.rows());
      IndexList parents;
      for (int k = 0; k < 40; ++k) parents.push_back(s.def[static_cast<std::size_t>(k * 29) % s.def.size()]);
      s.p.conservativeResize(old + 40, 3);
      s.previous.conservativeResize(old + 40, 3);
      s.r.conservativeResize(old + 40);
      for (Index k = 0; k < 40; ++k) {
        const Index par = parents[static_cast<std::size_t>(k)];
        s.p.row(old + k) = s.p.row(par) + Eigen::RowVector3d(0.01 * u(s.rng), 0.01 * u(s.rng), 0.0);
        s.previous.row(old + k) = s.p.row(old + k);  // a new row starts where it is
        s.r[old + k] = s.r[par];
        s.def.push_back(old + k);
      }
      zero.on_inserted(s.p, s.r, parents);
      def.on_inserted(s.p, s.r, parents);
    }
    if (step == 30) {  // removals: every seventh deformable row
      std::vector<bool> keep(static_cast<std::size_t>(s.p.rows()), true);
      for (std::size_t q = 0; q < s.def.size(); q += 7) keep[static_cast<std::size_t>(s.def[q])] = false;
      zero.on_removed(keep);
      def.on_removed(keep);
      Index w = 0;
      IndexList new_row(keep.size(), -1);
      for (std::size_t i = 0; i < keep.size(); ++i) {
        if (!keep[i]) continue;
        new_row[i] = w;
        s.p.row(w) = s.p.row(static_cast<Index>(i));
        s.previous.row(w) = s.previous.row(static_cast<Index>(i));
        s.r[w] = s.r[static_cast<Index>(i)];
        s.r_before[w] = s.r_before[static_cast<Index>(i)];
        ++w;
      }
      s.p.conservativeResize(w, 3);
      s.previous.conservativeResize(w, 3);
      s.r.conservativeResize(w);
      s.r_before.conservativeResize(w);
      IndexList kept;
      for (Index d : s.def)
        if (keep[static_cast<std::size_t>(d)]) kept.push_back(new_row[static_cast<std::size_t>(d)]);
      s.def = kept;
    }
    const auto [shift, reach] = s.shift_reach();
    BvhCounters c = def.step_bounded(s.p, s.previous, s.r, shift, reach);
    CollectRows narrow;
    collide(zero, def, SatMode::Lite, narrow, c);
    std::set<Index> seen;
    for (Index row : narrow.rows) ASSERT_TRUE(seen.insert(row).second) << "row " << row << " reported twice";
    const std::set<Index> truth = s.brute();
    for (Index row : truth) ASSERT_TRUE(seen.count(row)) << "step " << step << " missed deformable row " << row;
    total_truth += truth.size();
    if (kind == 1) idle_refits += static_cast<std::size_t>(c.nu);
  }
  EXPECT_GT(total_truth, 0u);  // the sheets do meet
  // Lazy: an idle step refits only the leaves near the zero sheet, not every leaf.
  EXPECT_LT(idle_refits, 10 * leaves);
}

// The hull of the zero balls as a second pruning test (collide's `hull`, used with OBB and sphere zero trees):
// against each zero box kind, every deformable row whose ball overlaps a zero ball is still a candidate on
// every step of a drag down through the zero sheet with idle jitter in between, and the hull prunes work
// (fewer overlap tests in all than without it over the steps the sheets are apart).
template <class ZeroBox>
void check_hull_pruning(const char* kind) {
  Drag s(2000, 800, 0.45);
  Bvh<ZeroBox> zero(s.p, s.r, s.zero, BvhParams{});
  Aabb hull;
  for (Index z : s.zero) hull.expand(s.p.row(z).transpose(), s.r[z]);
  BvhParams dp;
  dp.update = UpdateMode::Bounded;
  Bvh<Aabb> with(s.p, s.r, s.def, dp), without(s.p, s.r, s.def, dp);
  Index nv_with = 0, nv_without = 0;
  std::size_t total_truth = 0;
  for (int step = 0; step < 40; ++step) {
    s.previous = s.p;
    s.r_before = s.r;
    for (Index d : s.def) {
      if (step % 2 == 0) s.p(d, 2) -= 0.025;  // down through the sheet
      else s.p(d, 0) += (step % 4 == 1 ? 1e-4 : -1e-4);  // idle jitter
    }
    const auto [shift, reach] = s.shift_reach();
    BvhCounters a = with.step_bounded(s.p, s.previous, s.r, shift, reach);
    BvhCounters b = without.step_bounded(s.p, s.previous, s.r, shift, reach);
    CollectRows got, plain;
    collide(zero, with, SatMode::Lite, got, a, &hull);
    collide(zero, without, SatMode::Lite, plain, b);
    const std::set<Index> seen(got.rows.begin(), got.rows.end());
    const std::set<Index> truth = s.brute();
    for (Index row : truth) ASSERT_TRUE(seen.count(row)) << kind << " step " << step << " missed deformable row " << row;
    total_truth += truth.size();
    nv_with += a.nv;
    nv_without += b.nv;
  }
  EXPECT_GT(total_truth, 0u) << kind;  // the sheets do meet
  EXPECT_LE(nv_with, nv_without) << kind;
}

TEST(BvhBounded, HullPruningKeepsEveryOverlap) {
  check_hull_pruning<Aabb>("aabb");
  check_hull_pruning<Obb>("obb");
  check_hull_pruning<Sphere>("sphere");
}

// A box grown by a tree's bound holds every ball of its rows after any number of idle steps, even at
// 1e6 offsets (the outward rounding), and a fitted leaf is exactly its rows' tight box.
TEST(BvhBounded, BoundsHoldTheBallsFarFromTheOrigin) {
  Drag s(500, 400, 0.3);
  for (Index i = 0; i < s.p.rows(); ++i) s.p.row(i) += Eigen::RowVector3d(1e6, -1e6, 1e6);
  BvhParams dp;
  dp.update = UpdateMode::Bounded;
  Bvh<Aabb> def(s.p, s.r, s.def, dp);
  for (int step = 0; step < 200; ++step) {
    s.previous = s.p;
    s.r_before = s.r;
    for (Index d : s.def) s.p(d, 1) += (step % 2 ? 3e-5 : -3e-5);
    const auto [shift, reach] = s.shift_reach();
    def.step_bounded(s.p, s.previous, s.r, shift, reach);
    for (std::int32_t k = 0; k < static_cast<std::int32_t>(def.nodes().size()); ++k) {
      const Aabb b = def.bound(k);
      def.for_each_row(k, [&](Index row) {
        ASSERT_TRUE(b.contains(s.p.row(row).transpose(), s.r[row] + s.t_of(row))) << "node " << k << " row " << row;
      });
    }
  }
  // Refit one leaf: it is now fitted, and its box is the tight box of its balls (within the safety factor).
  std::int32_t leaf = 0;
  while (!def.node(leaf).leaf()) leaf = def.node(leaf).first_child;
  BvhCounters c;
  EXPECT_TRUE(def.refit_leaf(leaf, c));
  EXPECT_TRUE(def.fitted(leaf));
  EXPECT_FALSE(def.refit_leaf(leaf, c));  // once per step
  Aabb tight;
  def.for_each_row(leaf, [&](Index row) { tight.expand(s.p.row(row).transpose(), s.r[row] + s.t_of(row)); });
  EXPECT_TRUE(def.box(leaf).contains(tight));
  EXPECT_LT((def.box(leaf).hi - tight.hi).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
