// Bvh<Box> build and traversals: structure and invariants for every box kind, surfel/tree
// candidates against brute force, tree/tree candidates against brute force (no false negatives,
// each deformable surfel at most once per step), the extended narrow policy.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <set>

#include "bvh_test_util.hpp"
#include "surfeledit/core/bvh/extended.hpp"
#include "surfeledit/core/bvh/overlap.hpp"
#include "surfeledit/core/bvh/traversal.hpp"
#include "surfeledit/core/scene.hpp"

namespace {

using namespace bvh_test;

template <class Box>
void check_structure(const BvhParams& params) {
  Points p;
  Values r;
  make_sheet(5000, 11, p, r);
  IndexList rows;  // a subset, as a zero region is
  for (Index i = 0; i < p.rows(); i += 2) rows.push_back(i);
  Bvh<Box> t(p, r, rows, params);
  ASSERT_FALSE(t.empty());
  EXPECT_TRUE(check_invariants(t, p, r));
  EXPECT_EQ(t.surfel_count(), static_cast<Index>(rows.size()));
  IndexList sorted = t.order();
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, rows);
  int max_level = 0;
  for (const auto& nd : t.nodes()) {
    max_level = std::max(max_level, nd.level);
    if (nd.leaf()) {
      EXPECT_GE(nd.size(), params.leaf_min_surfels);
      if (nd.level < params.max_level) EXPECT_LE(nd.size(), params.leaf_max_surfels);
    } else {
      EXPECT_EQ(t.node(nd.first_child).begin, nd.begin);
      EXPECT_EQ(t.node(nd.first_child).end, t.node(nd.first_child + 1).begin);
      EXPECT_EQ(t.node(nd.first_child + 1).end, nd.end);
    }
  }
  EXPECT_LE(max_level, params.max_level);
  EXPECT_EQ(t.height(), max_level + 1);
  EXPECT_FALSE(t.refit_since_build());
  EXPECT_GT(t.memory_bytes(), t.nodes().size() * sizeof(Box));
  // Insertions: children split off random tree rows, placed nearby, are covered at once.
  std::mt19937_64 rng(12);
  std::normal_distribution<double> g(0.0, 0.05);
  IndexList parents;
  for (int k = 0; k < 100; ++k) parents.push_back(rows[static_cast<std::size_t>(k * 17) % rows.size()]);
  const Index old = static_cast<Index>(p.rows());
  p.conservativeResize(old + 100, 3);
  r.conservativeResize(old + 100);
  for (Index k = 0; k < 100; ++k) {
    p.row(old + k) = p.row(parents[static_cast<std::size_t>(k)]) + Eigen::RowVector3d(g(rng), g(rng), g(rng));
    r[old + k] = r[parents[static_cast<std::size_t>(k)]];
  }
  t.on_inserted(p, r, parents);
  EXPECT_EQ(t.surfel_count(), static_cast<Index>(rows.size()) + 100);
  EXPECT_TRUE(t.refit_since_build());
  EXPECT_TRUE(check_invariants(t, p, r));
}

TEST(BvhTree, BuildInvariantsAllKinds) {
  BvhParams params;
  check_structure<Aabb>(params);
  check_structure<Obb>(params);
  check_structure<Sphere>(params);
  params.max_level = 5;  // stops by level: leaves bigger than leaf_max_surfels
  params.leaf_min_surfels = 3;
  params.leaf_max_surfels = 8;
  params.min_leaf_extent = 0.2;
  check_structure<Aabb>(params);
  check_structure<Obb>(params);
  check_structure<Sphere>(params);
}

TEST(BvhTree, MinLeafExtent) {
  Points p;
  Values r;
  make_sheet(2000, 3, p, r);
  BvhParams params;
  params.min_leaf_extent = 0.3;
  Bvh<Aabb> a(p, r, all_rows(2000), params);
  Bvh<Obb> o(p, r, all_rows(2000), params);
  for (const auto& nd : a.nodes())
    if (nd.leaf()) EXPECT_GE((nd.box.hi - nd.box.lo).minCoeff(), 0.3 - 1e-12);
  for (const auto& nd : o.nodes())
    if (nd.leaf()) EXPECT_GE(nd.box.ext.minCoeff(), 0.15 - 1e-12);
  EXPECT_TRUE(check_invariants(a, p, r));
  EXPECT_TRUE(check_invariants(o, p, r));
}

TEST(BvhTree, ValidatesParams) {
  BvhParams bad;
  bad.leaf_min_surfels = 0;
  EXPECT_THROW(validate(bad), Error);
  bad = {};
  bad.leaf_max_surfels = 1;
  bad.leaf_min_surfels = 2;
  EXPECT_THROW(validate(bad), Error);
  bad = {};
  bad.hybrid_f = 1.5;
  EXPECT_THROW(validate(bad), Error);
  EXPECT_EQ(parse_update("hybrid"), UpdateMode::Hybrid);
  EXPECT_THROW(parse_update("sideways"), Error);
}

template <class Box>
void check_surfel_queries() {
  Points p;
  Values r;
  make_sheet(4000, 21, p, r);
  Bvh<Box> t(p, r, all_rows(4000));
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-1.1, 1.1), uz(-0.4, 0.4), ur(0.0, 0.1);
  std::vector<std::int32_t> fifo;
  for (int q = 0; q < 300; ++q) {
    const Sphere s{Vec3(u(rng), u(rng), uz(rng)), ur(rng)};
    BvhCounters c;
    std::set<Index> cand;
    query_surfel(t, s, [&](std::int32_t leaf) {
      t.for_each_row(leaf, [&](Index row) { cand.insert(row); });
      return true;
    }, c, fifo);
    for (Index i = 0; i < p.rows(); ++i) {
      const Sphere si{p.row(i).transpose(), r[i]};
      if (overlap(s, si)) ASSERT_TRUE(cand.count(i)) << "query " << q << " missed row " << i;
    }
    EXPECT_GE(c.nv, 1);
  }
}

TEST(BvhTree, SurfelQueryHasNoFalseNegatives) {
  check_surfel_queries<Aabb>();
  check_surfel_queries<Obb>();
  check_surfel_queries<Sphere>();
}

// Zero region: a bumpy sheet at z = 0; deformable: a smaller sheet coming down from above.
struct TwoSheets {
  Points p;
  Values r;
  IndexList zero, def;
  TwoSheets(int nz, int nd, double z_def) {
    Points pz, pd;
    Values rz, rd;
    make_sheet(nz, 31, pz, rz);
    make_sheet(nd, 32, pd, rd, z_def, 0.5);
    p.resize(nz + nd, 3);
    p << pz, pd;
    r.resize(nz + nd);
    r << rz, rd;
    for (int i = 0; i < nz; ++i) zero.push_back(i);
    for (int i = 0; i < nd; ++i) def.push_back(nz + i);
  }
  // Deformable rows whose sphere overlaps some zero sphere (brute force).
  std::set<Index> brute() const {
    std::set<Index> out;
    for (Index d : def)
      for (Index z : zero)
        if (overlap(Sphere{p.row(d).transpose(), r[d]}, Sphere{p.row(z).transpose(), r[z]})) {
          out.insert(d);
          break;
        }
    return out;
  }
};

template <class ZeroBox>
void check_tree_tree(SatMode sat, UpdateMode update) {
  TwoSheets s(3000, 1000, 0.6);
  BvhParams zp;
  Bvh<ZeroBox> zero(s.p, s.r, s.zero, zp);
  BvhParams dp;
  dp.update = update;
  dp.hybrid_f = 0.5;
  Bvh<Aabb> def(s.p, s.r, s.def, dp);
  std::int64_t total_candidates = 0;
  std::size_t total_brute = 0;
  for (int step = 0; step < 12; ++step) {
    // Move the deformable sheet down and bend it a little.
    for (Index d : s.def) {
      s.p(d, 2) -= 0.06;
      s.p(d, 0) += 0.01 * std::sin(3.0 * s.p(d, 1) + step);
    }
    BvhCounters c = def.refit(s.p, s.r);
    CollectRows narrow;
    collide(zero, def, sat, narrow, c);
    std::set<Index> seen;
    for (Index row : narrow.rows) ASSERT_TRUE(seen.insert(row).second) << "row " << row << " reported twice";
    const std::set<Index> truth = s.brute();
    for (Index row : truth) ASSERT_TRUE(seen.count(row)) << "step " << step << " missed deformable row " << row;
    for (Index row : seen) ASSERT_GE(row, static_cast<Index>(s.zero.size()));  // only deformable rows
    EXPECT_EQ(c.np, static_cast<std::int64_t>(narrow.rows.size()));
    total_candidates += c.np;
    total_brute += truth.size();
  }
  EXPECT_GT(total_brute, 0u);  // the sheets do meet
  EXPECT_GE(total_candidates, static_cast<std::int64_t>(total_brute));
}

TEST(BvhTree, TreeTreeHasNoFalseNegativesEachRowOnce) {
  for (UpdateMode m : {UpdateMode::BottomUp, UpdateMode::TopDown, UpdateMode::Hybrid}) {
    SCOPED_TRACE(to_string(m));
    check_tree_tree<Aabb>(SatMode::Lite, m);
    check_tree_tree<Obb>(SatMode::Lite, m);
    check_tree_tree<Obb>(SatMode::Full, m);
    check_tree_tree<Sphere>(SatMode::Lite, m);
  }
}

TEST(BvhTree, TreeTreeFarApartTestsOnlyTheRoots) {
  TwoSheets s(3000, 1000, 5.0);
  Bvh<Aabb> zero(s.p, s.r, s.zero);
  Bvh<Aabb> def(s.p, s.r, s.def);
  BvhCounters c = def.refit(s.p, s.r);
  CollectRows narrow;
  collide(zero, def, SatMode::Lite, narrow, c);
  EXPECT_TRUE(narrow.rows.empty());
  EXPECT_EQ(c.nv, 1);
  EXPECT_EQ(c.np, 0);
}

// Extended narrow phase vs the same rule applied to every deformable surfel each step.
TEST(BvhTree, ExtendedNarrowMatchesFullRuleAndCachesState) {
  auto solid = make_sphere(1.0);
  const SampledSurfels s = solid->sample(SampleParams{0.04, 3, 0.25});
  const Index n = static_cast<Index>(s.positions.rows());
  std::vector<std::uint8_t> is_zero(static_cast<std::size_t>(n));
  IndexList zero, def;
  for (Index i = 0; i < n; ++i) {
    is_zero[static_cast<std::size_t>(i)] = s.positions(i, 2) < 0.0;
    (is_zero[static_cast<std::size_t>(i)] ? zero : def).push_back(i);
  }
  auto original = std::make_shared<const InsideOutside>(s.positions, s.normals);
  ExtendedNarrow with_tree(original, is_zero, n);
  ExtendedNarrow everyone(original, is_zero, n);
  Bvh<Aabb> zt(s.positions, s.radii, zero);
  Bvh<Aabb> dt(s.positions, s.radii, def);
  Points cur = s.positions, prev;
  std::int64_t candidates = 0;
  for (int step = 1; step <= 15; ++step) {
    prev = cur;
    for (Index d : def) cur(d, 2) -= 0.015;  // the upper cap sinks into the lower half
    BvhCounters c = dt.refit(cur, s.radii);
    with_tree.begin_step(step, cur, prev);
    collide(zt, dt, SatMode::Lite, with_tree, c);
    everyone.begin_step(step, cur, prev);
    for (Index d : def) everyone(d);
    candidates += c.np;
    EXPECT_EQ(with_tree.colliding_rows(), everyone.colliding_rows()) << "step " << step;
  }
  EXPECT_FALSE(with_tree.colliding_rows().empty());
  // With the cache, a surfel that is a candidate in consecutive steps costs one evaluation.
  EXPECT_LT(with_tree.evaluations(), 2 * candidates);
  EXPECT_EQ(everyone.evaluations(), static_cast<std::int64_t>(def.size()) * (15 + 1));
}

}  // namespace
