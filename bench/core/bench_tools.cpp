// Tools (issue 11 §1): what a tool's step costs when another tool changed rows it treats as rigid since
// its last step (its detector follows the moved rows or is re-initialised, EditSession::sync_tool) against
// a step of a tool working alone. Scene: the two-arm scene (core/two_arms.hpp) at
// spacing 0.004 (~215k surfels, ~27k per arm); tool "a" moves arm A, tool "b" arm B, by +-0.002 in x
// (no collision); one thread.
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_tools [--benchmark_repetitions=N]
// Arguments: 0 = robust, 1 = simple, 2 = temporal; BM_StepAfterOtherTool's second: 1 = incremental
// (on_rigid_moved), 0 = re-initialisation. Counters: surfels, deformable (arm A).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/two_arms.hpp"

namespace {

using namespace surfeledit;

const char* kAlgorithms[] = {"robust", "simple", "temporal"};

struct Arms {
  TwoArms scene{SampleParams{0.004, 1, 0.25}};
  std::unique_ptr<EditSession> session;
  const IdList& a = scene.a;
  Arms(const char* algorithm, bool incremental) {
    SessionParams params{1};
    params.incremental_rigid = incremental;
    session = std::make_unique<EditSession>("bench", params);
    session->load(scene.model());
    for (const char* tool : {"a", "b"})
      session->configure({{"algorithm", std::string(algorithm)}, {"threads", std::int64_t{1}}}, tool);
    session->set_regions({TwoArms::join(scene.body, scene.b), {}}, {scene.a, {}}, "a");
    session->set_regions({TwoArms::join(scene.body, scene.a), {}}, {scene.b, {}}, "b");
  }
  void move(const char* tool, double dx) {
    DeformParams p;
    p.translation = Vec3(dx, 0, 0);
    session->deform(p, tool);
  }
};

// Tool a steps back and forth; nothing else changes (no re-initialisation).
void BM_StepAlone(benchmark::State& state) {
  Arms arms(kAlgorithms[state.range(0)], true);
  double dx = 0.002;
  for (auto _ : state) {
    arms.move("a", dx);
    dx = -dx;
  }
  state.counters["surfels"] = static_cast<double>(arms.session->model().size());
  state.counters["deformable"] = static_cast<double>(arms.a.size());
}

// Tool b steps (not timed), then tool a: a's detector follows arm B's moved rows (on_rigid_moved) before
// its step; with the second argument 0 it is re-initialised instead (SessionParams::incremental_rigid).
void BM_StepAfterOtherTool(benchmark::State& state) {
  Arms arms(kAlgorithms[state.range(0)], state.range(1) != 0);
  double dx = 0.002;
  for (auto _ : state) {
    state.PauseTiming();
    arms.move("b", -dx);
    state.ResumeTiming();
    arms.move("a", dx);
    dx = -dx;
  }
  state.counters["surfels"] = static_cast<double>(arms.session->model().size());
  state.counters["deformable"] = static_cast<double>(arms.a.size());
}

BENCHMARK(BM_StepAlone)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StepAfterOtherTool)->ArgsProduct({{0, 1, 2}, {1, 0}})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
