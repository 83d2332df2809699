// Deforming AABB trees: after any random sequence of refits (bottom-up, top-down, hybrid),
// insertions and removals, every box contains its surfels and every parent its children
// (property test, fixed seeds). Plus the per-axis masks, the status flag and the counters.
#include <gtest/gtest.h>

#include <random>

#include "bvh_test_util.hpp"
#include "surfeledit/core/bvh/rebuilder.hpp"
#include "surfeledit/core/bvh/traversal.hpp"

namespace {

using namespace bvh_test;

// Smooth random deformation plus jitter: a random translation, a twist and per-surfel noise.
void deform(Points& p, const IndexList& rows, std::mt19937_64& rng, double amount) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 t(u(rng), u(rng), u(rng));
  const double twist = amount * u(rng);
  for (Index i : rows) {
    if (i >= p.rows()) continue;
    const double x = p(i, 0), y = p(i, 1);
    const double a = twist * p(i, 2);
    p(i, 0) = std::cos(a) * x - std::sin(a) * y;
    p(i, 1) = std::sin(a) * x + std::cos(a) * y;
    p.row(i) += amount * (t.transpose() + 0.3 * Eigen::RowVector3d(u(rng), u(rng), u(rng)));
  }
}

void run_property(UpdateMode mode, double f, double inflation, std::uint64_t seed) {
  SCOPED_TRACE(std::string(to_string(mode)) + " f=" + std::to_string(f) + " seed=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  Points p;
  Values r;
  make_sheet(3000, seed, p, r);
  BvhParams params;
  params.update = mode;
  params.hybrid_f = f;
  params.inflation = inflation;
  params.min_leaf_extent = 0.01;
  params.leaf_max_surfels = 8;
  IndexList rows = all_rows(static_cast<Index>(p.rows()));
  Bvh<Aabb> t(p, r, rows, params);
  ASSERT_TRUE(check_invariants(t, p, r));
  std::uniform_int_distribution<int> what(0, 3);
  for (int step = 0; step < 40; ++step) {
    const int op = what(rng);
    if (op == 0 && p.rows() > 500) {
      // Remove ~3% of the rows; the model compacts its arrays.
      std::vector<bool> keep(static_cast<std::size_t>(p.rows()), true);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      for (auto&& k : keep) k = u(rng) > 0.03;
      Points np(std::count(keep.begin(), keep.end(), true), 3);
      Values nr(np.rows());
      Index w = 0;
      for (Index i = 0; i < p.rows(); ++i)
        if (keep[static_cast<std::size_t>(i)]) {
          np.row(w) = p.row(i);
          nr[w++] = r[i];
        }
      p = np;
      r = nr;
      t.on_removed(keep);
      EXPECT_EQ(t.surfel_count(), static_cast<Index>(p.rows()));
    } else if (op == 1) {
      // Split ~2% of the rows: children appended near their parents, with half the radius.
      IndexList parents;
      std::uniform_int_distribution<Index> pick(0, static_cast<Index>(p.rows()) - 1);
      for (int k = 0; k < p.rows() / 50; ++k) parents.push_back(pick(rng));
      const Index old = static_cast<Index>(p.rows());
      p.conservativeResize(old + static_cast<Index>(parents.size()), 3);
      r.conservativeResize(p.rows());
      std::normal_distribution<double> g(0.0, 0.02);
      for (std::size_t k = 0; k < parents.size(); ++k) {
        const Index row = old + static_cast<Index>(k);
        p.row(row) = p.row(parents[k]) + Eigen::RowVector3d(g(rng), g(rng), g(rng));
        r[row] = 0.5 * r[parents[k]];
      }
      t.on_inserted(p, r, parents);
      EXPECT_EQ(t.surfel_count(), static_cast<Index>(p.rows()));
      ASSERT_TRUE(check_invariants(t, p, r)) << "after insertion, step " << step;
    }
    deform(p, all_rows(static_cast<Index>(p.rows())), rng, 0.02);
    BvhCounters c = t.refit(p, r);
    // A random partial traversal (the top-down part happens on visit).
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<std::int32_t> fifo;
    query_surfel(t, Sphere{Vec3(u(rng), u(rng), 0.0), 0.2}, [](std::int32_t) { return true; }, c, fifo);
    // Visit everything before inspecting every box.
    t.touch_all(c);
    ASSERT_TRUE(check_invariants(t, p, r)) << "step " << step;
    EXPECT_TRUE(t.refit_since_build());
  }
}

TEST(BvhUpdate, PropertyAllStrategiesWithInsertionsAndRemovals) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    run_property(UpdateMode::BottomUp, 1.0, 0.0, seed);
    run_property(UpdateMode::BottomUp, 1.0, 0.01, seed);
    run_property(UpdateMode::TopDown, 0.0, 0.0, seed);
    run_property(UpdateMode::Hybrid, 0.25, 0.0, seed);
    run_property(UpdateMode::Hybrid, 0.5, 0.005, seed);
    run_property(UpdateMode::Hybrid, 0.75, 0.0, seed);
  }
}

// In bottom-up mode the invariants hold right after refit(), without any traversal.
TEST(BvhUpdate, BottomUpHoldsWithoutTraversal) {
  std::mt19937_64 rng(17);
  Points p;
  Values r;
  make_sheet(4000, 17, p, r);
  BvhParams params;
  params.update = UpdateMode::BottomUp;
  Bvh<Aabb> t(p, r, all_rows(4000), params);
  for (int step = 0; step < 20; ++step) {
    deform(p, all_rows(4000), rng, 0.03);
    t.refit(p, r);
    ASSERT_TRUE(check_invariants(t, p, r)) << step;
  }
}

// Selective propagation: a move along x only recomputes x; nothing moves -> nothing propagates.
TEST(BvhUpdate, SelectiveRefitPropagatesOnlyChangedAxes) {
  Points p;
  Values r;
  make_sheet(4000, 23, p, r);
  BvhParams params;
  params.update = UpdateMode::BottomUp;
  Bvh<Aabb> t(p, r, all_rows(4000), params);
  const Bvh<Aabb> before = t;
  BvhCounters idle = t.refit(p, r);
  EXPECT_FALSE(t.refit_since_build());  // nothing escaped: the tree is still "fresh"
  std::int64_t leaves = 0;
  for (const auto& nd : t.nodes()) leaves += nd.leaf();
  EXPECT_EQ(idle.nu, leaves);  // every leaf checked, no parent recomputed
  // Move one surfel along +x far enough to escape its leaf and the root.
  p(0, 0) += 5.0;
  BvhCounters moved = t.refit(p, r);
  EXPECT_TRUE(t.refit_since_build());
  EXPECT_EQ(moved.nu, leaves + t.node(0).level + [&] {  // leaves + the ancestors of that leaf
              std::int64_t depth = 0;
              for (const auto& nd : t.nodes())
                if (nd.leaf()) {
                  bool has = false;
                  for (std::int32_t s = nd.begin; s < nd.end; ++s) has |= t.order()[s] == 0;
                  if (has) depth = nd.level;
                }
              return depth;
            }());
  for (std::size_t k = 0; k < t.nodes().size(); ++k) {
    // y and z untouched everywhere.
    EXPECT_EQ(t.nodes()[k].box.lo[1], before.nodes()[k].box.lo[1]);
    EXPECT_EQ(t.nodes()[k].box.hi[2], before.nodes()[k].box.hi[2]);
  }
  EXPECT_GE(t.node(0).box.hi[0], p(0, 0) + r[0]);
  EXPECT_TRUE(check_invariants(t, p, r));
}

// Lazy (top-down) refit only touches what a traversal visits.
TEST(BvhUpdate, TopDownRefitsOnlyVisitedNodes) {
  Points p;
  Values r;
  make_sheet(4000, 29, p, r);
  BvhParams bu, td;
  bu.update = UpdateMode::BottomUp;
  td.update = UpdateMode::TopDown;
  Bvh<Aabb> a(p, r, all_rows(4000), bu), b(p, r, all_rows(4000), td);
  p.col(2).array() += 0.01;
  BvhCounters ca = a.refit(p, r), cb = b.refit(p, r);
  std::vector<std::int32_t> fifo;
  const Sphere far{Vec3(10, 10, 10), 0.1};
  query_surfel(a, far, [](std::int32_t) { return true; }, ca, fifo);
  b.touch(0, cb);  // what a traversal does on visiting the root
  query_surfel(b, far, [](std::int32_t) { return true; }, cb, fifo);
  EXPECT_EQ(cb.nu, 1);
  EXPECT_GT(ca.nu, 100);
}

TEST(BvhUpdate, StatusFreshRefitRebuilding) {
  Points p;
  Values r;
  make_sheet(20000, 41, p, r);
  BvhParams params;
  params.update = UpdateMode::BottomUp;
  Bvh<Aabb> t(p, r, all_rows(20000), params);
  BvhRebuilder<Aabb> rb;
  EXPECT_EQ(status_of(t, rb), BvhStatus::Fresh);
  p.col(0).array() += 0.5;
  t.refit(p, r);
  EXPECT_EQ(status_of(t, rb), BvhStatus::Refit);
  ASSERT_TRUE(rb.start(p, r, all_rows(20000), params));
  EXPECT_FALSE(rb.start(p, r, all_rows(20000), params));  // one at a time
  std::unique_ptr<Bvh<Aabb>> fresh;
  while (!(fresh = rb.take())) {
    EXPECT_NE(status_of(t, rb), BvhStatus::Fresh);
    std::this_thread::yield();
  }
  t = std::move(*fresh);
  EXPECT_EQ(status_of(t, rb), BvhStatus::Fresh);
  EXPECT_STREQ(to_string(BvhStatus::Rebuilding), "rebuilding");
}

}  // namespace
