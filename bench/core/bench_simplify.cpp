// Simplification benchmark (issue 5, thesis Table 9.1 and §9.4.4): clustering time by region growing
// and hierarchical clustering at cluster sizes 10 / 20 / 50 / 100 (plus 18, the thesis's ~18 surfels
// per cluster) on ~150k surfels, with the cluster counts; sphere cluster tree build times both ways
// (leaves of ~18 and ~120 surfels). Sizes 15 (region growing) and 27 (hierarchical) give about the
// thesis's 8,297 clusters of ~18 on 150k surfels. One thread, as the thesis's 700 MHz P3.
//
// Model: the cup with handle (scene.hpp), sampled to ~150k surfels (curved everywhere, thin walls,
// a handle: the clusters see every kind of neighbourhood).
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_simplify [--benchmark_repetitions=N] [--benchmark_out=out.json --benchmark_out_format=json]
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>

#include "surfeledit/core/scene.hpp"
#include "surfeledit/core/simplify/clustering.hpp"
#include "surfeledit/core/simplify/simplified_surfel.hpp"
#include "surfeledit/core/simplify/sphere_tree.hpp"

namespace {

using namespace surfeledit;

struct Fixture {
  SampledSurfels s;
  IndexList rows;
};
Fixture* g = nullptr;

Fixture make_fixture() {
  auto cup = make_cup();
  const int target = 150000;
  double spacing = std::sqrt(cup->area() / target);
  SampledSurfels s = cup->sample(SampleParams{spacing, 7, 0.25});
  spacing *= std::sqrt(static_cast<double>(s.positions.rows()) / target);
  Fixture f;
  f.s = cup->sample(SampleParams{spacing, 7, 0.25});
  f.rows.resize(static_cast<std::size_t>(f.s.positions.rows()));
  for (Index r = 0; r < static_cast<Index>(f.rows.size()); ++r) f.rows[r] = r;
  return f;
}

SimplifyParams params_of(SimplifyMethod m, int size) {
  SimplifyParams p;
  p.method = m;
  p.cluster_size = size;
  p.threads = 1;
  return p;
}

// Clustering plus one simplified surfel per cluster (what a reset of the approximate detector does).
void BM_Simplify(benchmark::State& state) {
  const auto method = static_cast<SimplifyMethod>(state.range(0));
  const SimplifyParams p = params_of(method, static_cast<int>(state.range(1)));
  Index clusters = 0;
  for (auto _ : state) {
    const Clustering c = make_clusters(g->s.positions, g->rows, p);
    const std::vector<SimplifiedSurfel> simple = simplify(g->s.positions, g->s.normals, g->s.radii, c, 1);
    benchmark::DoNotOptimize(simple.data());
    clusters = c.size();
  }
  state.SetLabel(to_string(method));
  state.counters["surfels"] = static_cast<double>(g->rows.size());
  state.counters["clusters"] = clusters;
  state.counters["mean_size"] = static_cast<double>(g->rows.size()) / clusters;
}

void BM_SphereTree(benchmark::State& state) {
  const bool hierarchical = state.range(0) == 1;
  const SimplifyParams p = params_of(hierarchical ? SimplifyMethod::Hierarchical : SimplifyMethod::RegionGrowing,
                                     static_cast<int>(state.range(1)));
  SphereClusterTree t;
  for (auto _ : state) {
    t = hierarchical ? SphereClusterTree::build_hierarchical(g->s.positions, g->s.radii, g->rows, p)
                     : SphereClusterTree::build_region_growing(g->s.positions, g->s.radii, g->rows, p);
    benchmark::DoNotOptimize(t.nodes().data());
  }
  state.SetLabel(hierarchical ? "hierarchical" : "region_growing");
  state.counters["leaves"] = t.leaf_count();
  state.counters["mean_leaf"] = static_cast<double>(g->rows.size()) / t.leaf_count();
  state.counters["height"] = t.height();
  state.counters["cluster_ms"] = t.cluster_ms();
  state.counters["root_radius"] = t.nodes()[0].sphere.radius;
}

void simplify_args(benchmark::internal::Benchmark* b) {
  for (int m : {1, 2})
    for (int size : {10, 15, 18, 20, 27, 50, 100}) b->Args({m, size});
}

BENCHMARK(BM_Simplify)->Apply(simplify_args)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_SphereTree)->Args({1, 18})->Args({0, 18})->Args({1, 120})->Args({0, 120})->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

int main(int argc, char** argv) {
  Fixture f = make_fixture();
  g = &f;
  std::printf("cup with handle: %zu surfels\n", f.rows.size());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
