// Blend tool benchmarks at full size (issue 10 §6): the boolean of two 100k-surfel models (two overlapping
// spheres of ~100k samples each, union / intersection / difference) and filling a hole of 5% of a 100k-surfel
// sphere's surface (a polar cap, ~5k surfels cut away); each on a fresh session (loading untimed). Threads as
// the session's default (all) unless --threads=1 is set via SURFELEDIT_BENCH_THREADS.
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_blend [--benchmark_repetitions=N]
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/particles/blend.hpp"
#include "surfeledit/core/scene.hpp"

namespace {

using namespace surfeledit;

int bench_threads() {
  const char* t = std::getenv("SURFELEDIT_BENCH_THREADS");
  return t ? std::atoi(t) : 1;
}

SurfelArrays sphere_samples(double radius, const Vec3& centre, std::uint64_t seed, double spacing) {
  Pose p;
  p.translation = centre;
  SampleParams sp;
  sp.spacing = spacing;
  sp.seed = seed;
  const SampledSurfels s = make_sphere(radius, p)->sample(sp);
  SurfelArrays a;
  a.positions = s.positions;
  a.normals = s.normals;
  a.radii = s.radii;
  return a;
}

// ~100k samples on a unit sphere.
constexpr double kSpacing = 0.0112;

void BM_Boolean100k(benchmark::State& bench) {
  const BooleanOp op = static_cast<BooleanOp>(bench.range(0));
  const SurfelArrays a = sphere_samples(1.0, Vec3::Zero(), 1, kSpacing);
  const SurfelArrays b = sphere_samples(1.0, Vec3(0.8, 0.3, 0.1), 2, kSpacing);
  std::size_t features = 0;
  for (auto _ : bench) {
    bench.PauseTiming();
    EditSession s("bench", SessionParams{bench_threads()});
    s.load(SurfelModel::from_arrays(a));
    SurfelArrays copy = b;
    bench.ResumeTiming();
    features = s.boolean(op, std::move(copy)).features.size();
  }
  bench.counters["surfels_a"] = static_cast<double>(a.positions.rows());
  bench.counters["surfels_b"] = static_cast<double>(b.positions.rows());
  bench.counters["features"] = static_cast<double>(features);
}

void BM_FillHole5Percent(benchmark::State& bench) {
  const SurfelArrays all = sphere_samples(1.0, Vec3::Zero(), 3, kSpacing);
  // A polar cap of 5% of the area: z > 0.9 ((1 - cos theta) / 2 = 0.05).
  SurfelArrays holed;
  Eigen::Index kept = 0;
  for (Eigen::Index k = 0; k < all.positions.rows(); ++k) kept += all.positions(k, 2) <= 0.9;
  holed.positions.resize(kept, 3);
  holed.normals.resize(kept, 3);
  holed.radii.resize(kept);
  for (Eigen::Index k = 0, j = 0; k < all.positions.rows(); ++k) {
    if (all.positions(k, 2) > 0.9) continue;
    holed.positions.row(j) = all.positions.row(k);
    holed.normals.row(j) = all.normals.row(k);
    holed.radii[j++] = all.radii[k];
  }
  std::size_t inserted = 0;
  for (auto _ : bench) {
    bench.PauseTiming();
    EditSession s("bench", SessionParams{bench_threads()});
    s.load(SurfelModel::from_arrays(holed));
    bench.ResumeTiming();
    HoleParams p;
    p.max_diameter = 1.0;
    inserted = s.fill_holes(p).inserted.size();
  }
  bench.counters["surfels"] = static_cast<double>(holed.positions.rows());
  bench.counters["cut"] = static_cast<double>(all.positions.rows() - holed.positions.rows());
  bench.counters["inserted"] = static_cast<double>(inserted);
}

// The final projection of a blend alone (iterations = 0): range(0) particles on a unit sphere with radial
// noise, spacing ~ mean radius, projection tangent (0: nothing) or mls (1), one thread.
void BM_FinalProjection(benchmark::State& bench) {
  const int count = static_cast<int>(bench.range(0));
  Points x(count, 3), n(count, 3);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / count, rho = std::sqrt(1.0 - z * z), phi = golden * i;
    n.row(i) << rho * std::cos(phi), rho * std::sin(phi), z;
    x.row(i) = (1.0 + 0.01 * std::sin(37.0 * i)) * n.row(i);
  }
  BlendParams p;
  p.iterations = 0;
  p.threads = 1;
  p.projection = bench.range(1) == 1 ? ProjectionKind::Mls : ProjectionKind::Tangent;
  const double mean_radius = std::sqrt(4.0 * M_PI / count);
  for (auto _ : bench) benchmark::DoNotOptimize(run_blend(x, n, Points(), mean_radius, p).positions.data());
  bench.counters["particles"] = count;
}

BENCHMARK(BM_FinalProjection)->ArgNames({"particles", "mls"})->Args({2067, 0})->Args({2067, 1})->Args({200000, 1})
    ->Unit(benchmark::kMillisecond)->Repetitions(3);
BENCHMARK(BM_Boolean100k)->ArgNames({"op"})->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);
BENCHMARK(BM_FillHole5Percent)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

}  // namespace

BENCHMARK_MAIN();
