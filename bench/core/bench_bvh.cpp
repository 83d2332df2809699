// BVH benchmark (issue 4): build time AABB vs OBB vs sphere on ~150k and ~60k surfels, refit vs
// rebuild of the 60k-surfel deformable AABB tree, and a step with no collision (refit + tree/tree,
// and the surfel/tree variant), all on one thread.
//
// Scene ("near miss"): a rigid slab 3 x 3 x 0.3 turned 45 degrees about z (zero region, ~150k
// surfels) and a sphere of radius 0.5 (deformable, ~60k surfels) beside one of its side faces, 0.03
// model units away (about 4 surfel spacings). The sphere lies inside the slab's root AABB, so the
// traversal has to descend, but no surfel sphere touches a zero surfel sphere.
// Every timed step moves every deformable surfel (the sign alternates, so the shape oscillates).
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_bvh [--benchmark_repetitions=N] [--benchmark_out=out.json --benchmark_out_format=json]
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <string>

#include "surfeledit/core/bvh/bvh.hpp"
#include "surfeledit/core/bvh/obb.hpp"
#include "surfeledit/core/bvh/sphere.hpp"
#include "surfeledit/core/bvh/traversal.hpp"
#include "surfeledit/core/scene.hpp"

namespace {

using namespace surfeledit;
using namespace surfeledit::bvh;

struct Fixture {
  Points positions;  // slab rows first, then sphere rows
  Values radii;
  IndexList zero, def;
  long moves = 0;
};
Fixture* g = nullptr;

SampledSurfels sample_count(const Solid& solid, int target) {
  // Spacing for ~target samples: count ~ area / spacing^2, corrected once by a trial.
  double spacing = std::sqrt(solid.area() / target);
  SampledSurfels s = solid.sample(SampleParams{spacing, 7, 0.25});
  spacing *= std::sqrt(static_cast<double>(s.positions.rows()) / target);
  return solid.sample(SampleParams{spacing, 7, 0.25});
}

Fixture make_fixture() {
  Pose turned;
  turned.rotation = Eigen::AngleAxisd(M_PI / 4.0, Vec3::UnitZ()).toRotationMatrix();
  auto slab = make_box(Vec3(1.5, 1.5, 0.15), turned);
  Pose beside;  // outward normal of a side face of the turned slab: (1, 1, 0) / sqrt(2)
  beside.translation = (1.5 + 0.5 + 0.03) * Vec3(1.0, 1.0, 0.0).normalized();
  auto sphere = make_sphere(0.5, beside);
  const SampledSurfels b = sample_count(*slab, 150000);
  const SampledSurfels s = sample_count(*sphere, 60000);
  Fixture f;
  const Eigen::Index nb = b.positions.rows(), ns = s.positions.rows();
  f.positions.resize(nb + ns, 3);
  f.positions << b.positions, s.positions;
  f.radii.resize(nb + ns);
  f.radii << b.radii, s.radii;
  for (Index i = 0; i < nb; ++i) f.zero.push_back(i);
  for (Index i = 0; i < ns; ++i) f.def.push_back(static_cast<Index>(nb) + i);
  return f;
}

// Moves every deformable surfel: +-(0, 0.005, 0.003) model units, alternating.
void move_deformable() {
  const double sign = (g->moves++ % 2 == 0) ? 1.0 : -1.0;
  for (Index i : g->def) {
    g->positions(i, 1) += 0.005 * sign;
    g->positions(i, 2) += 0.003 * sign;
  }
}

template <class Box>
void build(benchmark::State& state, bool zero_region) {
  const IndexList& rows = zero_region ? g->zero : g->def;
  for (auto _ : state) {
    Bvh<Box> t(g->positions, g->radii, rows);
    benchmark::DoNotOptimize(t.nodes().data());
    state.counters["nodes"] = static_cast<double>(t.nodes().size());
    state.counters["height"] = t.height();
    state.counters["MB"] = static_cast<double>(t.memory_bytes()) / 1e6;
  }
  state.counters["surfels"] = static_cast<double>(rows.size());
}

void refit(benchmark::State& state, UpdateMode mode) {
  BvhParams params;
  params.update = mode;
  Bvh<Aabb> t(g->positions, g->radii, g->def, params);
  BvhCounters sum;
  for (auto _ : state) {
    state.PauseTiming();
    move_deformable();
    state.ResumeTiming();
    const BvhCounters c = t.refit(g->positions, g->radii);
    benchmark::DoNotOptimize(c);
    sum += c;
  }
  state.counters["Nu"] = benchmark::Counter(static_cast<double>(sum.nu), benchmark::Counter::kAvgIterations);
}

void rebuild(benchmark::State& state) {
  BvhParams params;
  for (auto _ : state) {
    state.PauseTiming();
    move_deformable();
    state.ResumeTiming();
    Bvh<Aabb> t(g->positions, g->radii, g->def, params);
    benchmark::DoNotOptimize(t.nodes().data());
  }
}

// One step without collision: refit the deformable tree, then the tree/tree test.
template <class ZeroBox>
void step_tree_tree(benchmark::State& state, UpdateMode mode, SatMode sat) {
  const Bvh<ZeroBox> zero(g->positions, g->radii, g->zero);
  BvhParams params;
  params.update = mode;
  Bvh<Aabb> def(g->positions, g->radii, g->def, params);
  BvhCounters sum;
  CollectRows narrow;
  for (auto _ : state) {
    state.PauseTiming();
    move_deformable();
    narrow.rows.clear();
    state.ResumeTiming();
    BvhCounters c = def.refit(g->positions, g->radii);
    collide(zero, def, sat, narrow, c);
    benchmark::DoNotOptimize(narrow.rows.data());
    sum += c;
  }
  // Per step (averaged over iterations; the two alternating poses differ a little).
  const auto avg = benchmark::Counter::kAvgIterations;
  state.counters["Nv"] = benchmark::Counter(static_cast<double>(sum.nv), avg);
  state.counters["Np"] = benchmark::Counter(static_cast<double>(sum.np), avg);
  state.counters["Nu"] = benchmark::Counter(static_cast<double>(sum.nu), avg);
}

// One step without collision, zero tree only: every deformable surfel queries the zero tree.
template <class ZeroBox>
void step_surfel_tree(benchmark::State& state) {
  const Bvh<ZeroBox> zero(g->positions, g->radii, g->zero);
  std::vector<std::int32_t> fifo;
  BvhCounters c;
  std::size_t hits = 0;
  for (auto _ : state) {
    state.PauseTiming();
    move_deformable();
    state.ResumeTiming();
    for (Index i : g->def) {
      const Sphere s{g->positions.row(i).transpose(), g->radii[i]};
      query_surfel(zero, s, [&](std::int32_t) {
        ++hits;
        return false;  // one overlapping leaf suffices: the narrow test is a global query
      }, c, fifo);
    }
    benchmark::DoNotOptimize(hits);
  }
  const auto avg = benchmark::Counter::kAvgIterations;
  state.counters["Nv"] = benchmark::Counter(static_cast<double>(c.nv), avg);
  state.counters["Np"] = benchmark::Counter(static_cast<double>(hits), avg);  // surfels reaching a leaf
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  Fixture fixture = make_fixture();
  g = &fixture;
  benchmark::AddCustomContext("surfels_zero", std::to_string(fixture.zero.size()));
  benchmark::AddCustomContext("surfels_deformable", std::to_string(fixture.def.size()));
  std::fprintf(stderr, "fixture: zero (slab) %zu surfels, deformable (sphere) %zu surfels\n", fixture.zero.size(),
               fixture.def.size());

  const auto ms = benchmark::kMillisecond;
  benchmark::RegisterBenchmark("build/aabb/slab", build<Aabb>, true)->Unit(ms);
  benchmark::RegisterBenchmark("build/obb/slab", build<Obb>, true)->Unit(ms);
  benchmark::RegisterBenchmark("build/sphere/slab", build<Sphere>, true)->Unit(ms);
  benchmark::RegisterBenchmark("build/aabb/sphere", build<Aabb>, false)->Unit(ms);
  benchmark::RegisterBenchmark("build/obb/sphere", build<Obb>, false)->Unit(ms);
  benchmark::RegisterBenchmark("build/sphere/sphere", build<Sphere>, false)->Unit(ms);
  benchmark::RegisterBenchmark("rebuild/aabb/sphere", rebuild)->Unit(ms);
  benchmark::RegisterBenchmark("refit/bottom_up/sphere", refit, UpdateMode::BottomUp)->Unit(ms);
  benchmark::RegisterBenchmark("refit/hybrid_0.5/sphere", refit, UpdateMode::Hybrid)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/aabb-aabb/bottom_up", step_tree_tree<Aabb>, UpdateMode::BottomUp,
                               SatMode::Lite)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/aabb-aabb/hybrid_0.5", step_tree_tree<Aabb>, UpdateMode::Hybrid,
                               SatMode::Lite)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/aabb-aabb/top_down", step_tree_tree<Aabb>, UpdateMode::TopDown,
                               SatMode::Lite)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/obb-aabb/hybrid_0.5/sat_lite", step_tree_tree<Obb>,
                               UpdateMode::Hybrid, SatMode::Lite)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/obb-aabb/hybrid_0.5/sat_full", step_tree_tree<Obb>,
                               UpdateMode::Hybrid, SatMode::Full)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/sphere-aabb/hybrid_0.5", step_tree_tree<Sphere>,
                               UpdateMode::Hybrid, SatMode::Lite)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/aabb-surfels", step_surfel_tree<Aabb>)->Unit(ms);
  benchmark::RegisterBenchmark("step_no_collision/obb-surfels", step_surfel_tree<Obb>)->Unit(ms);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
