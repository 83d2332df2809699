// The server's share of "update written" after one step of the ~1M-surfel drag (issue 14): what the
// request thread does once the step's reply is out -- the copy of the moved rows out of the model
// (prepare_update; a step's event lists the rows the step moved) -- and, for a watcher of the compact
// encoding, the publisher thread's encoding of every part (encode_compact, parts of max_chunk_surfels).
// BM_ChangesEvent: the rows changed since a version, what the server lists instead when a slow watcher's
// queue is over its bound and queued steps are merged into one update (Service::Impl::coalesce).
// Not included: Cyclone's CDR serialisation and delivery of the samples (dds_write), which happen only
// while a reader of that encoding is matched (RESULTS §29).
//
// Scene: 1,008,480 surfels (the piercing drag's count) with 288,256 F1 rows (its deformable count),
// random positions and normals; one translation step, algorithm none. One thread.
//
//     taskset -c 1 build/bench/surfeledit_bench_update_build [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <random>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/service/update.hpp"
#include "surfeledit/service/update_compact.hpp"

namespace surfeledit::service {
namespace {

constexpr Index kSurfels = 1008480;
constexpr Index kMoved = 288256;
constexpr std::uint64_t kChunk = 65536;  // ServiceConfig::max_chunk_surfels' default

// A session after one step that moved kMoved rows (built once).
struct Drag {
  EditSession session{"bench", SessionParams{1}};
  std::uint64_t before = 0;  // the version before the step
  Drag() {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    SurfelArrays a;
    a.positions.resize(kSurfels, 3);
    a.normals.resize(kSurfels, 3);
    a.radii = Values::Constant(kSurfels, 0.005);
    for (Index i = 0; i < kSurfels; ++i) {
      a.positions.row(i) = Vec3(u(rng), u(rng), i < kSurfels - kMoved ? -1.0 + 0.1 * u(rng) : 0.5 + 0.4 * u(rng));
      a.normals.row(i) = Vec3(u(rng), u(rng), 1.0).normalized();
    }
    session.load(SurfelModel::from_arrays(a));
    IdList zero, one;
    for (Index i = 0; i < kSurfels; ++i) (i < kSurfels - kMoved ? zero : one).push_back(static_cast<SurfelId>(i));
    session.configure({{"algorithm", std::string("none")}});
    session.set_regions({zero, {}}, {one, {}});
    before = session.version();
    DeformParams p;
    p.translation = Vec3(0.0, 0.0, -0.001);
    session.deform(p);
  }
};

Drag& drag() {
  static Drag d;
  return d;
}

void BM_ChangesEvent(benchmark::State& state) {
  Drag& d = drag();
  std::size_t rows = 0;
  for (auto _ : state) {
    UpdateEvent e = changes_event(d.session, "bench", d.before);
    rows = e.rows.size();
    benchmark::DoNotOptimize(e.rows.data());
  }
  state.counters["rows"] = static_cast<double>(rows);
}
BENCHMARK(BM_ChangesEvent)->Unit(benchmark::kMillisecond);

void BM_PrepareUpdate(benchmark::State& state) {
  Drag& d = drag();
  const UpdateEvent e = changes_event(d.session, "bench", d.before);
  for (auto _ : state) {
    PreparedUpdate p = prepare_update(e, &d.session.model());
    benchmark::DoNotOptimize(p.positions.data());
  }
}
BENCHMARK(BM_PrepareUpdate)->Unit(benchmark::kMillisecond);

void BM_EncodeCompact(benchmark::State& state) {
  Drag& d = drag();
  const PreparedUpdate p = prepare_update(changes_event(d.session, "bench", d.before), &d.session.model());
  for (auto _ : state) {
    for (std::uint32_t part = 0; part < update_parts(p, kChunk); ++part) {
      const UpdateChunk c = update_chunk(p, part, kChunk);
      CompactSurfels s = encode_compact(p, c.begin, c.count);
      benchmark::DoNotOptimize(s.positions.data());
    }
  }
}
BENCHMARK(BM_EncodeCompact)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace surfeledit::service

BENCHMARK_MAIN();
