// Particle engine benchmark in the thesis Table 12.1 configuration: 2,067 particles on a curved patch
// (39 x 53 jittered grid, spacing 1, bent on a cylinder of radius 20), neighbourhood radius 3.6 (~40
// neighbours), 50 iterations, one thread. Cases: neighbourhood cached (one k-d tree query), recomputed every
// iteration with the uniform grid, recomputed with the k-d tree.
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_particles [--benchmark_repetitions=N] [--benchmark_out=out.json]
// Each benchmark iteration is the whole 50-iteration blend; see the median aggregate.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "surfeledit/core/particles/engine.hpp"

namespace {

using namespace surfeledit;

ParticleState make_patch() {
  std::mt19937_64 rng(12);  // fixed: same particles every run
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int rows = 39, cols = 53;
  const double bend = 20.0;
  Points x(rows * cols, 3), n(rows * cols, 3);
  for (int a = 0; a < rows; ++a)
    for (int b = 0; b < cols; ++b) {
      const int i = a * cols + b;
      const double s = b + 0.2 * u(rng), angle = s / bend;
      x.row(i) << a + 0.2 * u(rng), bend * std::sin(angle), bend * (1.0 - std::cos(angle)) + 0.1 * u(rng);
      n.row(i) << 0.05 * u(rng), -std::sin(angle), std::cos(angle);
    }
  return ParticleState::from_surfels(x, n);
}

void BM_Blend50(benchmark::State& bench, NeighbourMode mode) {
  const ParticleState start = make_patch();
  ParticleParams p;
  p.weight.radius = 3.6;
  p.dt = 0.015;  // below the engine's stable step here, so no sub-steps
  p.neighbours = mode;
  p.threads = 1;
  double neighbours = 0.0;
  int substeps = 0;
  for (auto _ : bench) {
    ParticleEngine engine(start, Points(), p);  // includes the initial neighbourhood query
    for (int it = 0; it < 50; ++it) substeps += engine.step().substeps;
    neighbours = static_cast<double>(engine.neighbourhood().indices.size()) / engine.state().size();
    benchmark::DoNotOptimize(engine.state().x.data());
  }
  bench.counters["particles"] = static_cast<double>(start.size());
  bench.counters["neighbours"] = neighbours;
  bench.counters["substeps_per_run"] = static_cast<double>(substeps) / bench.iterations();
}

BENCHMARK_CAPTURE(BM_Blend50, cached_kdtree, NeighbourMode::Cached)->Unit(benchmark::kMillisecond)->Repetitions(15);
BENCHMARK_CAPTURE(BM_Blend50, recompute_grid, NeighbourMode::RecomputeGrid)->Unit(benchmark::kMillisecond)->Repetitions(15);
BENCHMARK_CAPTURE(BM_Blend50, recompute_kdtree, NeighbourMode::RecomputeKdTree)->Unit(benchmark::kMillisecond)->Repetitions(15);

}  // namespace

BENCHMARK_MAIN();
