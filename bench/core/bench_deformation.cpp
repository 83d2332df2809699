// Deformation-step benchmark: in-process time of ONE surfeledit::apply_step on one thread for
// ~60k deformable surfels (sphere: top cap = one region F1, rest = blend) over a large rigid slab
// (zero region F0, ~400k surfels). Fields (lambda, grad lambda) are computed once, outside timing.
//
// Run (the binary is built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_deformation [--repetitions=N] [--deformable=60000]
//       [--benchmark_out=out.json --benchmark_out_format=json]
// Each repetition times exactly one step (Iterations(1)), so the aggregates over N repetitions
// (default 500) are the distribution of single steps: mean, median, p99, max, in microseconds.
// Successive steps alternate the sign of the translation / angle so the shape oscillates in place
// instead of drifting; every step still moves all deformable surfels.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"

namespace {

using namespace surfeledit;

struct Fixture {
  Points positions, normals;
  DeformationFields fields;
  std::size_t zero = 0, one = 0, blend = 0;
};

Fixture* g_fixture = nullptr;

// Slab (F0) + sphere with ~`deformable` samples (F1 = top quarter of the sphere by height, blend = rest).
Fixture make_fixture(int deformable) {
  const std::uint64_t seed = 7;  // fixed: same samples every run
  // Rigid slab 3 x 3 x 0.3 model units centred at the origin; sphere radius 0.5 centred at z = 1.
  auto slab = make_box(Vec3(1.5, 1.5, 0.15));
  Pose above;
  above.translation = Vec3(0.0, 0.0, 1.0);
  auto sphere = make_sphere(0.5, above);
  // Spacing for ~`deformable` sphere samples: count ~ area / spacing^2, corrected once by a trial.
  double spacing = std::sqrt(sphere->area() / deformable);
  SampledSurfels s = sphere->sample(SampleParams{spacing, seed, 0.25});
  spacing *= std::sqrt(static_cast<double>(s.positions.rows()) / deformable);
  s = sphere->sample(SampleParams{spacing, seed, 0.25});
  const SampledSurfels b = slab->sample(SampleParams{spacing, seed, 0.25});

  Fixture f;
  const Eigen::Index nb = b.positions.rows(), ns = s.positions.rows();
  f.positions.resize(nb + ns, 3);
  f.normals.resize(nb + ns, 3);
  f.positions << b.positions, s.positions;
  f.normals << b.normals, s.normals;
  std::vector<Region> regions(static_cast<std::size_t>(nb + ns), Region::Zero);
  for (Eigen::Index i = 0; i < ns; ++i) {
    // Top quarter of the sphere's height (z above centre + r/2) is F1, the rest blends.
    const bool top = s.positions(i, 2) > 1.0 + 0.25;
    regions[static_cast<std::size_t>(nb + i)] = top ? Region::One : Region::Blend;
    (top ? f.one : f.blend) += 1;
  }
  f.zero = static_cast<std::size_t>(nb);
  f.fields = compute_fields(f.positions, regions, /*threads=*/0);  // setup only: all threads
  return f;
}

// One step per repetition; `rotate` adds a rotation about x through F1's centroid (the default centre).
void step(benchmark::State& state, bool rotate) {
  static long counter = 0;
  Fixture& f = *g_fixture;
  for (auto _ : state) {
    const double sign = (counter++ % 2 == 0) ? 1.0 : -1.0;
    DeformParams p;
    p.translation = Vec3(0.0, 0.01 * sign, 0.005 * sign);  // model units (sphere radius 0.5)
    if (rotate) {
      p.axis = Vec3(1.0, 0.0, 0.0);
      p.angle = 0.05 * sign;  // radians (~2.9 degrees)
    }
    DeformResult r = apply_step(f.fields, p, f.positions, f.normals, nullptr, nullptr, /*threads=*/1);
    benchmark::DoNotOptimize(r.moved.data());
    state.counters["moved"] = static_cast<double>(r.moved.size());
  }
}

double percentile(const std::vector<double>& v, double q) {
  std::vector<double> s(v);
  std::sort(s.begin(), s.end());
  const double pos = q * static_cast<double>(s.size() - 1);  // linear interpolation between ranks
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, s.size() - 1);
  return s[lo] + (pos - static_cast<double>(lo)) * (s[hi] - s[lo]);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  int repetitions = 500, deformable = 60000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--repetitions=", 0) == 0) repetitions = std::atoi(a.c_str() + 14);
    else if (a.rfind("--deformable=", 0) == 0) deformable = std::atoi(a.c_str() + 13);
    else {
      std::fprintf(stderr, "unknown argument %s\n", argv[i]);
      return 2;
    }
  }
  Fixture fixture = make_fixture(deformable);
  g_fixture = &fixture;
  benchmark::AddCustomContext("surfels_total", std::to_string(fixture.positions.rows()));
  benchmark::AddCustomContext("surfels_zero", std::to_string(fixture.zero));
  benchmark::AddCustomContext("surfels_one", std::to_string(fixture.one));
  benchmark::AddCustomContext("surfels_blend", std::to_string(fixture.blend));
  benchmark::AddCustomContext("surfels_deformable", std::to_string(fixture.fields.deformable.size()));
  std::fprintf(stderr, "fixture: %lld surfels, zero %zu, one %zu, blend %zu (deformable %zu)\n",
               static_cast<long long>(fixture.positions.rows()), fixture.zero, fixture.one, fixture.blend,
               fixture.fields.deformable.size());

  for (const bool rotate : {false, true}) {
    benchmark::RegisterBenchmark(rotate ? "step/translate+rotate/threads:1" : "step/translate/threads:1", step, rotate)
        ->Unit(benchmark::kMicrosecond)
        ->Iterations(1)
        ->Repetitions(repetitions)
        ->ReportAggregatesOnly(true)
        ->ComputeStatistics("p99", [](const std::vector<double>& v) { return percentile(v, 0.99); })
        ->ComputeStatistics("max", [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); });
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
