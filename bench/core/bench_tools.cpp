// Tools (issue 11 §1): what a tool's step costs when another tool changed rows it treats as rigid since
// its last step (its detector is re-initialised from the model, EditSession::sync_tool) against a step
// of a tool working alone. Scene: a box body with two capsule arms (as tests/core/test_tool.cpp) at
// spacing 0.004 (~215k surfels, ~27k per arm); tool "a" moves arm A, tool "b" arm B, by +-0.002 in x
// (no collision); one thread.
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   build/bench/surfeledit_bench_tools [--benchmark_repetitions=N]
// Arguments: 0 = robust, 1 = simple, 2 = temporal. Counters: surfels, deformable (arm A).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"

namespace {

using namespace surfeledit;

const char* kAlgorithms[] = {"robust", "simple", "temporal"};

struct Arms {
  std::unique_ptr<EditSession> session = std::make_unique<EditSession>("bench", SessionParams{1});
  IdList a, b;
  explicit Arms(const char* algorithm) {
    Scene scene;
    scene.add(make_box(Vec3(0.7, 0.2, 0.2)));
    Pose pa, pb;
    pa.translation = Vec3(-0.4, 0, 0.52);
    pb.translation = Vec3(0.4, 0, 0.52);
    scene.add(make_capsule(0.1, 0.25, pa));
    scene.add(make_capsule(0.1, 0.25, pb));
    const SampledSurfels s = scene.sample(SampleParams{0.004, 1, 0.25});
    SurfelArrays m;
    m.positions = s.positions;
    m.normals = s.normals;
    m.radii = s.radii;
    session->load(SurfelModel::from_arrays(m));
    IdList body;
    for (std::size_t i = 0; i < s.part.size(); ++i) (s.part[i] == 0 ? body : s.part[i] == 1 ? a : b).push_back(i);
    auto join = [](IdList x, const IdList& y) {
      x.insert(x.end(), y.begin(), y.end());
      std::sort(x.begin(), x.end());
      return x;
    };
    for (const char* tool : {"a", "b"})
      session->configure({{"algorithm", std::string(algorithm)}, {"threads", std::int64_t{1}}}, tool);
    session->set_regions({join(body, b), {}}, {a, {}}, "a");
    session->set_regions({join(body, a), {}}, {b, {}}, "b");
  }
  void move(const char* tool, double dx) {
    DeformParams p;
    p.translation = Vec3(dx, 0, 0);
    session->deform(p, tool);
  }
};

// Tool a steps back and forth; nothing else changes (no re-initialisation).
void BM_StepAlone(benchmark::State& state) {
  Arms arms(kAlgorithms[state.range(0)]);
  double dx = 0.002;
  for (auto _ : state) {
    arms.move("a", dx);
    dx = -dx;
  }
  state.counters["surfels"] = static_cast<double>(arms.session->model().size());
  state.counters["deformable"] = static_cast<double>(arms.a.size());
}

// Tool b steps (not timed), then tool a: a's detector is re-initialised before its step.
void BM_StepAfterOtherTool(benchmark::State& state) {
  Arms arms(kAlgorithms[state.range(0)]);
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
BENCHMARK(BM_StepAfterOtherTool)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
