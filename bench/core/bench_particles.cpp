// Particle engine benchmark in the thesis Table 12.1 configuration: 2,067 particles on a curved patch
// (39 x 53 jittered grid, spacing 1, bent on a cylinder of radius 20), neighbourhood radius 3.6 (~40
// neighbours), 50 iterations, one thread. Cases: neighbourhood cached (one range query: grid builder), recomputed every
// iteration with the uniform grid, recomputed with the k-d tree. Scaling: the same patch (density, radius,
// bend angle) at ~2k, ~20k and ~200k particles, iterations only (engine construction untimed), 5 per run
// at 20k and 200k: per-iteration time and pair interactions per second (unordered neighbour pairs
// evaluated, each giving forces and torques to both particles).
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

ParticleState make_patch(int rows = 39, int cols = 53) {
  std::mt19937_64 rng(12);  // fixed: same particles every run
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double bend = 20.0 * cols / 53.0;  // the same bend angle at every size (radius 20 at 53 columns)
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
  double neighbours = 0.0, pairs = 0.0;
  int substeps = 0;
  for (auto _ : bench) {
    ParticleEngine engine(start, Points(), p);  // includes the initial neighbourhood query
    for (int it = 0; it < 50; ++it) {
      pairs += 0.5 * static_cast<double>(engine.neighbourhood().indices.size());
      substeps += engine.step().substeps;
    }
    neighbours = static_cast<double>(engine.neighbourhood().indices.size()) / engine.state().size();
    benchmark::DoNotOptimize(engine.state().x.data());
  }
  bench.counters["particles"] = static_cast<double>(start.size());
  bench.counters["neighbours"] = neighbours;
  bench.counters["substeps_per_run"] = static_cast<double>(substeps) / bench.iterations();
  // Unordered neighbour pairs evaluated per second of the whole run (construction and query included).
  bench.counters["pairs_per_s"] = benchmark::Counter(pairs, benchmark::Counter::kIsRate);
}

// rows x cols patch (range(0) x range(1)), range(2) iterations, cached (0) or recomputed-grid (1) neighbourhoods.
void BM_Scaling(benchmark::State& bench) {
  const ParticleState start = make_patch(static_cast<int>(bench.range(0)), static_cast<int>(bench.range(1)));
  ParticleParams p;
  p.weight.radius = 3.6;
  p.dt = 0.015;
  p.neighbours = bench.range(3) == 0 ? NeighbourMode::Cached : NeighbourMode::RecomputeGrid;
  p.threads = 1;
  const int iterations = static_cast<int>(bench.range(2));
  double pairs = 0.0;
  for (auto _ : bench) {
    bench.PauseTiming();  // the initial neighbourhood query is not part of the per-iteration time
    ParticleEngine engine(start, Points(), p);
    bench.ResumeTiming();
    for (int it = 0; it < iterations; ++it) {
      pairs += 0.5 * static_cast<double>(engine.neighbourhood().indices.size());
      engine.step();
    }
    benchmark::DoNotOptimize(engine.state().x.data());
  }
  bench.counters["particles"] = static_cast<double>(start.size());
  bench.counters["pairs_per_s"] = benchmark::Counter(pairs, benchmark::Counter::kIsRate);
}

BENCHMARK_CAPTURE(BM_Blend50, cached_kdtree, NeighbourMode::Cached)->Unit(benchmark::kMillisecond)->Repetitions(15);
BENCHMARK_CAPTURE(BM_Blend50, recompute_grid, NeighbourMode::RecomputeGrid)->Unit(benchmark::kMillisecond)->Repetitions(15);
BENCHMARK_CAPTURE(BM_Blend50, recompute_kdtree, NeighbourMode::RecomputeKdTree)->Unit(benchmark::kMillisecond)->Repetitions(15);

BENCHMARK(BM_Scaling)
    ->ArgNames({"rows", "cols", "iters", "grid"})
    ->Args({39, 53, 50, 0})
    ->Args({123, 168, 5, 0})
    ->Args({390, 530, 5, 0})
    ->Args({39, 53, 50, 1})
    ->Args({123, 168, 5, 1})
    ->Args({390, 530, 5, 1})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3);

}  // namespace

BENCHMARK_MAIN();
