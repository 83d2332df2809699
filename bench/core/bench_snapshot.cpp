// Session snapshots (docs/journal.md): what a snapshot costs and what it saves. Scene: the two-arm scene
// (core/two_arms.hpp) at spacing 0.004 (~215k surfels), two tools (arm A, arm B), Robust, one thread;
// each session has taken `steps` deformation steps (both tools alternating, +-0.002 in x, no collision).
//   BM_Save:      EditSession::save of the session after `steps` steps (the time a snapshot would block
//                 the request loop, serialisation only; the file write comes on top). Counters: bytes,
//                 history_entries (the entries the history bound kept).
//   BM_Restore:   EditSession::restore of that snapshot into a fresh session (recovery with a snapshot).
//   BM_Replay:    load, set_regions of both tools and the `steps` steps from scratch (what recovery by log
//                 replay re-computes in the core for the same state).
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   taskset -c 1 build/bench/surfeledit_bench_snapshot [--benchmark_repetitions=N]
#include <benchmark/benchmark.h>

#include <memory>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/two_arms.hpp"

namespace {

using namespace surfeledit;

const TwoArms& scene() {
  static const TwoArms s{SampleParams{0.004, 1, 0.25}};
  return s;
}

std::unique_ptr<EditSession> replay(int steps) {
  const TwoArms& sc = scene();
  auto s = std::make_unique<EditSession>("bench", SessionParams{1});
  s->load(sc.model());
  for (const char* tool : {"a", "b"}) s->configure({{"threads", std::int64_t{1}}}, tool);
  s->set_regions({TwoArms::join(sc.body, sc.b), {}}, {sc.a, {}}, "a");
  s->set_regions({TwoArms::join(sc.body, sc.a), {}}, {sc.b, {}}, "b");
  for (int k = 0; k < steps; ++k) {
    DeformParams p;
    const bool a = k % 2 == 0;
    p.translation = Vec3((k / 2) % 2 ? -0.002 : 0.002, 0, 0) * (a ? 1.0 : -1.0);
    s->deform(p, a ? "a" : "b");
  }
  return s;
}

void BM_Save(benchmark::State& state) {
  const auto s = replay(static_cast<int>(state.range(0)));
  std::size_t bytes = 0;
  for (auto _ : state) {
    SnapshotWriter w;
    s->save(w);
    bytes = w.bytes().size();
    benchmark::DoNotOptimize(w.bytes().data());
  }
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["history_entries"] = static_cast<double>(s->history().size());  // what undo can reach
}

void BM_Restore(benchmark::State& state) {
  SnapshotWriter w;
  replay(static_cast<int>(state.range(0)))->save(w);
  for (auto _ : state) {
    EditSession s("restored", SessionParams{1});
    SnapshotReader r(w.bytes());
    s.restore(r);
    benchmark::DoNotOptimize(s.version());
  }
  state.counters["bytes"] = static_cast<double>(w.bytes().size());
}

void BM_Replay(benchmark::State& state) {
  for (auto _ : state) {
    auto s = replay(static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(s->version());
  }
}

BENCHMARK(BM_Save)->Arg(0)->Arg(20)->Arg(80)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Restore)->Arg(0)->Arg(20)->Arg(80)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Replay)->Arg(0)->Arg(20)->Arg(80)->Unit(benchmark::kMillisecond)->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
