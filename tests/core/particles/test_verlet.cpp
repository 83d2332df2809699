// The Verlet list against a brute-force range query: after every move, small or large, its neighbourhood is
// exactly every other particle within the radius, rows ascending (the grid query's lists).
#include <gtest/gtest.h>

#include <random>

#include "particle_fixtures.hpp"
#include "surfeledit/core/particles/engine.hpp"
#include "surfeledit/core/particles/verlet.hpp"

namespace surfeledit {
namespace {

// All pairs: j in row i (ascending) exactly when j != i and |x_j - x_i| <= radius.
Neighbourhood brute_force(const Points& x, double radius) {
  Neighbourhood nb;
  nb.offsets.push_back(0);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index j = 0; j < x.rows(); ++j) {
      const double dx = x(j, 0) - x(i, 0), dy = x(j, 1) - x(i, 1), dz = x(j, 2) - x(i, 2);
      if (j != i && dx * dx + dy * dy + dz * dz <= radius * radius) nb.indices.push_back(static_cast<Index>(j));
    }
    nb.offsets.push_back(static_cast<std::int64_t>(nb.indices.size()));
  }
  return nb;
}

TEST(VerletList, EqualsAFreshRangeQueryAfterEveryMove) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double radius = 1.5, skin = 0.3;
  Points x(600, 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i) x.row(i) << 8 * u(rng), 8 * u(rng), 2 * u(rng);
  VerletList list;
  Neighbourhood nb;
  long checked_pairs = 0;
  for (int call = 0; call < 60; ++call) {
    // Mostly moves well below the skin (the list is reused), every tenth call one particle jumps far, and
    // in between moves about skin / 2 (just below and just above the rebuild threshold).
    const double step = call % 10 == 9 ? 0.0 : (call % 10 == 5 ? 0.16 : 0.02);
    for (Eigen::Index i = 0; i < x.rows(); ++i) x.row(i) += step * Vec3(u(rng), u(rng), u(rng)).normalized().transpose();
    if (call % 10 == 9) x.row(call % x.rows()) << 8 * u(rng), 8 * u(rng), 2 * u(rng);
    neighbours_verlet(x, radius, skin, 1, list, nb);
    const Neighbourhood truth = brute_force(x, radius);
    ASSERT_EQ(nb.offsets, truth.offsets) << "call " << call;
    ASSERT_EQ(nb.indices, truth.indices) << "call " << call;
    checked_pairs += static_cast<long>(truth.indices.size());
  }
  EXPECT_GT(checked_pairs, 60 * 600 * 5);  // ~15 neighbours each: the test is not vacuous
  EXPECT_GE(list.rebuilds, 7);             // every jump and every skin / 2 move rebuilt it ...
  EXPECT_LE(list.rebuilds, 30);            // ... and the small moves reused it
}

TEST(VerletList, ZeroSkinAndChangedRadiusAreFreshQueries) {
  Points x, n;
  test::fibonacci_sphere(500, 4.0, x, n);
  VerletList list;
  Neighbourhood nb;
  neighbours_verlet(x, 1.0, 0.0, 2, list, nb);
  EXPECT_EQ(nb.indices, brute_force(x, 1.0).indices);
  neighbours_verlet(x, 1.0, 0.2, 2, list, nb);
  neighbours_verlet(x, 1.3, 0.2, 2, list, nb);  // a larger radius must not reuse the list for 1.0 + 0.2
  EXPECT_EQ(nb.offsets, brute_force(x, 1.3).offsets);
  EXPECT_EQ(nb.indices, brute_force(x, 1.3).indices);
  EXPECT_EQ(list.rebuilds, 3);
}

TEST(VerletList, EngineRecomputedNeighbourhoodIsExactEveryIteration) {
  // A clump spreading under strong repulsion: particles cross many neighbourhoods, some fast.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Points x(200, 3), n(200, 3);
  for (int i = 0; i < 200; ++i) {
    x.row(i) << 3 * u(rng), 3 * u(rng), 0.1 * u(rng);
    n.row(i) << 0.1 * u(rng), 0.1 * u(rng), 1;
  }
  ParticleParams p;
  p.weight.radius = 1.2;
  p.repulsion.amplitude = 5.0;
  p.dt = 0.2;
  p.threads = 1;
  p.neighbours = NeighbourMode::RecomputeGrid;
  ParticleEngine engine(ParticleState::from_surfels(x, n), Points(), p);
  double moved = 0.0;
  for (int it = 0; it < 120; ++it) {
    const Points before = engine.state().x;
    engine.step();
    moved += (engine.state().x - before).rowwise().norm().maxCoeff();
    const Neighbourhood truth = brute_force(engine.state().x, p.weight.radius);
    ASSERT_EQ(engine.neighbourhood().offsets, truth.offsets) << "iteration " << it;
    ASSERT_EQ(engine.neighbourhood().indices, truth.indices) << "iteration " << it;
  }
  EXPECT_GT(moved, 2.0 * p.weight.radius);  // the particles did travel beyond their first neighbourhoods
}

}  // namespace
}  // namespace surfeledit
