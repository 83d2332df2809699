// Collision-response geometry benchmark (issue 9 §3): merge (union) + sharp crease + intersection
// curves on one thread, on the piercing scene at full size: a rigid plate (~150k surfels) and a ball
// (~60k, the one region) pushed down until its centre is in the plate's mid-plane, where ~6,500 of its
// surfels collide (Robust detector, outside timing).
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_merge [--benchmark_repetitions=N]
// Counters: colliding, removed, feature and moved surfels, copies, curves and curve points.
#include <benchmark/benchmark.h>

#include "response_scenes.hpp"
#include "surfeledit/core/response/crease.hpp"
#include "surfeledit/core/response/curves.hpp"
#include "surfeledit/core/response/merge.hpp"

namespace {

using namespace surfeledit;

// The piercing scene (as client_py's scenes.piercing): spacing 0.01, plate 2.592 x 2.592 x 0.15, ball
// radius 0.691 starting two spacings above the plate, moved down by its start height.
const testing::ResponseScene& piercing() {
  static const testing::ResponseScene scene = [] {
    const double h = 0.01, half_t = 0.075, r = 0.691, z0 = half_t + r + 2.0 * h;
    std::vector<std::unique_ptr<Solid>> zero, ball;
    zero.push_back(make_box(Vec3(1.296, 1.296, half_t)));
    Pose above;
    above.translation = Vec3(0, 0, z0);
    above.rotation = testing::generic_rotation(0.7);
    ball.push_back(make_sphere(r, above));
    testing::Motion down;
    down.translation = Vec3(0, 0, -z0);
    return testing::build_scene(std::move(zero), std::move(ball), down, h);
  }();
  return scene;
}

void BM_MergeCreaseCurves(benchmark::State& state) {
  const testing::ResponseScene& sc = piercing();
  const MergeParams mp;
  MergeResult m;
  CreaseResult c;
  std::vector<Curve> curves;
  for (auto _ : state) {
    m = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, sc.colliding, mp);
    c = crease(sc.model, m.features_deformable, m.features_zero);
    const IndexList rows = sc.model.rows_of(c.moved, "moved");
    Values radii(static_cast<Eigen::Index>(rows.size()));
    for (std::size_t k = 0; k < rows.size(); ++k) radii[static_cast<Eigen::Index>(k)] = sc.model.radii()[rows[k]];
    curves = intersection_curves(c.positions, radii);
    benchmark::DoNotOptimize(curves.data());
  }
  std::size_t points = 0;
  for (const Curve& cv : curves) points += static_cast<std::size_t>(cv.points.rows());
  state.counters["surfels"] = static_cast<double>(sc.model.size());
  state.counters["colliding"] = static_cast<double>(sc.colliding.size());
  state.counters["removed"] = static_cast<double>(m.removed.size());
  state.counters["candidates"] = static_cast<double>(m.stats.candidates);
  state.counters["queried"] = static_cast<double>(m.stats.queried);
  state.counters["features"] = static_cast<double>(m.features_deformable.size() + m.features_zero.size());
  state.counters["moved"] = static_cast<double>(c.moved.size());
  state.counters["copies"] = static_cast<double>(c.inserted_parents.size());
  state.counters["curves"] = static_cast<double>(curves.size());
  state.counters["curve_points"] = static_cast<double>(points);
}
BENCHMARK(BM_MergeCreaseCurves)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_MergeOnly(benchmark::State& state) {
  const testing::ResponseScene& sc = piercing();
  const MergeParams mp;
  for (auto _ : state) {
    MergeResult m = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, sc.colliding, mp);
    benchmark::DoNotOptimize(m.removed.data());
  }
}
BENCHMARK(BM_MergeOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
