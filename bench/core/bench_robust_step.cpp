// The Robust detector's step on the piercing scene (issue 14): the scene of surfeledit.scenes.piercing
// rebuilt in C++ (a 2.59 x 2.59 x 0.15 plate, the zero region, and a ball of radius 0.691, the one
// region, ~210k surfels at spacing 0.01, ~60k deformable), one thread, so that a profiler sees the
// steps alone and not the scenario's Python set-up.
//
// Run (built with -DSURFELEDIT_BUILD_BENCH=ON):
//   taskset -c 1 build/bench/surfeledit_bench_robust_step [--benchmark_repetitions=N]
//
// BM_PiercingRun/<history>/<hierarchy>: one iteration = the scenario's 50 steps (the ball pushed through
//   the plate) from a fresh session (set-up untimed). history 0: history_mb 0 (no before-image), 1: the
//   default; hierarchy 0: none, 1: zero AABB tree + deformable AABB tree. Counters: median and max
//   detect_ms over the steps, preprocess_ms (the detector's reset), re-tested surfels per step (median).
// BM_IdleDrag/<hierarchy>: one iteration = one step of +-1e-4 (a hundredth of the spacing) from the start
//   state: no point leaves its sphere, nothing is re-tested (checked); counters detect_ms (mean) and
//   history_kb_per_step (what 16 more such steps add to the undo history, per step).
// BM_IdleTurn/<threads>: BM_IdleDrag's step (no hierarchy) also turned by +-1e-6 rad, at 1 or 2 threads: no
//   displacement bound, so every row is checked against its sphere; counters deform_median_ms, detect_median_ms
//   (RESULTS §89.3: on two threads the deformation's rows had crossed to the other core's cache).
// BM_Preprocess/<tilted>: one iteration = configure(algorithm robust), i.e. one detector reset; tilted 1: the scene
//   turned as BM_DetectRunTilted's. BM_PreprocessTemporal/<tilted>: the same with algorithm temporal.
//   BM_PreprocessThreads/<tilted>, BM_PreprocessTemporalThreads/<tilted>: the same with the session's threads at 2
//   (wall time: the reset's parts that share nothing at once, at_once.hpp).
// BM_DetectRun/<config>, BM_DetectIdle/<config>: the detector alone (make_detector, reset, detect), the
//   same 50 steps / the same idle step with the positions moved untimed (the ball's rows translated; no
//   session, no history; the detect input carries the translation's displacement bound, as EditSession's).
//   <config> indexes kConfigs below (0: Robust without a hierarchy, 1: Robust with zero + deformable AABB
//   trees at the default update, 10: Simple without a hierarchy, 12: Temporal without a hierarchy, exact
//   queries; BM_DetectIdle runs every one). Counters: median / max thread CPU ms of one detect (detect_cpu_*), as the CPU column is of the whole
//   iteration; use them on a loaded machine; the broad phase's nv / np / nu and the queries (medians).
// BM_DetectRunTilted/<config>: BM_DetectRun on the scene turned by Piercing::tilt() (no face of the plate along an
//   axis): the same steps and queries, but the k-d trees' axis-aligned boxes fit the tilted plate loosely
//   (RESULTS §73: 4.9x BM_DetectRun's time with leaves of 48; §74: Simple's 33x before the turned frame).
// BM_DetectRunTwoTilts/<config>: the tilted scene with a second, larger zero plate far below it at another tilt, so
//   that the detectors' trees turn to that plate and the pierced one lies oblique in their frame (RESULTS §75: what
//   the nodes' oriented boxes still do once the trees turn).
#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"

namespace {

using namespace surfeledit;

constexpr double kSpacing = 0.01;      // surfel spacing of the full-size piercing scene, model units
constexpr double kHalfWidth = 1.296;   // plate half width
constexpr double kHalfThick = 0.075;   // plate half thickness
constexpr double kBall = 0.691;        // ball radius
constexpr int kSteps = 50;             // steps of the scenario

// The piercing scene, sampled once per process (as surfeledit.scenes.piercing(scale=1, seed=1)); tilted, the
// same scene turned by tilt() (positions, normals and the push), so that no surface of the plate lies along an axis
// of the k-d trees' boxes.
struct Piercing {
  SurfelArrays arrays;
  IdList zero, one;
  double z0 = 0.0;                      // the ball's start height above the plate's centre
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  // the scene's turn (identity unless tilted)

  static Eigen::Matrix3d tilt() { return Eigen::AngleAxisd(0.5, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix(); }

  // `kind`: 0 upright, 1 turned by tilt(), 2 turned by tilt() with a second, larger zero plate below it at another
  // tilt (so the detectors' trees turn to that plate, and the pierced one lies oblique in their frame).
  explicit Piercing(int kind) {
    const bool tilted = kind != 0;
    z0 = kHalfThick + kBall + 2.0 * kSpacing;
    Scene scene;
    scene.add(make_box(Vec3(kHalfWidth, kHalfWidth, kHalfThick)));
    Pose ball;
    ball.translation = Vec3(0.0, 0.0, z0);
    ball.rotation = Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
    scene.add(make_sphere(kBall, ball));
    if (kind == 2) {
      Pose below;
      below.translation = Vec3(0.0, 0.0, -4.0);
      below.rotation = Eigen::AngleAxisd(0.6, Vec3(-0.4, 0.9, 0.2).normalized()).toRotationMatrix();
      scene.add(make_box(Vec3(1.6, 1.6, kHalfThick), below));
    }
    const SampledSurfels s = scene.sample(SampleParams{kSpacing, 1, 0.25});
    arrays.positions = s.positions;
    arrays.normals = s.normals;
    if (tilted) {
      frame = tilt();
      arrays.positions = (s.positions * frame.transpose()).eval();
      arrays.normals = (s.normals * frame.transpose()).eval();
    }
    arrays.radii = s.radii;
    for (std::size_t i = 0; i < s.part.size(); ++i) (s.part[i] == 1 ? one : zero).push_back(i);
  }
  static const Piercing& get(int kind = 0) {
    if (kind == 2) {
      static const Piercing two(2);
      return two;
    }
    if (kind == 1) {
      static const Piercing turned(1);
      return turned;
    }
    static const Piercing upright(0);
    return upright;
  }
  // One step of the scenario's push (the ball through the plate in kSteps steps).
  Vec3 push() const {
    const Vec3 down(0.0, 0.0, -2.0 * z0 / kSteps);
    return frame.isIdentity(0.0) ? down : (frame * down).eval();
  }
  // A session with the scene loaded, its regions set and Robust configured (one thread).
  std::unique_ptr<EditSession> session(bool history, bool hierarchy, int threads = 1) const {
    auto s = std::make_unique<EditSession>("bench", SessionParams{threads});
    s->load(SurfelModel::from_arrays(arrays));
    s->set_regions({zero, {}}, {one, {}});
    std::vector<NamedSetting> set = {{"algorithm", std::string("robust")}, {"threads", std::int64_t{threads}}};
    if (!history) set.push_back({"history_mb", 0.0});
    if (hierarchy) {
      set.push_back({"zero_hierarchy", std::string("aabb")});
      set.push_back({"deformable_hierarchy", std::string("aabb")});
    }
    s->configure(set);
    return s;
  }
};

// CPU time of the calling thread, ms.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void BM_PiercingRun(benchmark::State& state) {
  const Piercing& scene = Piercing::get();
  DeformParams step;
  step.translation = scene.push();
  std::vector<double> detect, tested;
  double preprocess = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    auto session = scene.session(state.range(0) != 0, state.range(1) != 0);
    state.ResumeTiming();
    for (int k = 0; k < kSteps; ++k) {
      const StepResult r = session->deform(step);
      detect.push_back(r.stats.detect_ms);
      tested.push_back(static_cast<double>(r.stats.tested));
      preprocess = r.stats.preprocess_ms;
    }
    state.PauseTiming();
    session.reset();  // freed untimed
    state.ResumeTiming();
  }
  state.counters["detect_median_ms"] = median(detect);
  state.counters["detect_max_ms"] = *std::max_element(detect.begin(), detect.end());
  state.counters["preprocess_ms"] = preprocess;
  state.counters["retested_median"] = median(tested);
}

void BM_IdleDrag(benchmark::State& state) {
  const Piercing& scene = Piercing::get();
  auto session = scene.session(true, state.range(0) != 0);
  DeformParams step;
  step.translation = Vec3(1e-4, 0.0, 0.0);
  double detect = 0.0, n = 0.0;
  for (auto _ : state) {
    const StepResult r = session->deform(step);
    if (r.stats.tested != 0) throw std::runtime_error("idle drag re-tested surfels");
    detect += r.stats.detect_ms;
    n += 1.0;
    step.translation = -step.translation;
  }
  state.counters["detect_ms"] = detect / std::max(n, 1.0);
  // The undo history's growth per step (deterministic, unlike the times): 16 steps of a fresh session
  // (the timed one's history is at its bound by now).
  session = scene.session(true, state.range(0) != 0);
  auto history_bytes = [&] {
    for (const StructureInfo& s : session->report().structures)
      if (s.name == "history") return static_cast<double>(s.bytes);
    return 0.0;
  };
  const double h0 = history_bytes();
  for (int k = 0; k < 16; ++k, step.translation = -step.translation) session->deform(step);
  state.counters["history_kb_per_step"] = (history_bytes() - h0) / 16.0 / 1024.0;
}

// BM_IdleTurn/<threads>: BM_IdleDrag's step turned by +-1e-6 rad about the ball's centre as well, so that the step
// has no displacement bound and every row is checked against its sphere (none leaves it), at 1 or 2 threads.
void BM_IdleTurn(benchmark::State& state) {
  const Piercing& scene = Piercing::get();
  auto session = scene.session(true, false, static_cast<int>(state.range(0)));
  DeformParams step;
  step.translation = Vec3(1e-4, 0.0, 0.0);
  step.angle = 1e-6;
  std::vector<double> detect, deform;
  for (auto _ : state) {
    const StepResult r = session->deform(step);
    if (r.stats.tested != 0) throw std::runtime_error("idle turn re-tested surfels");
    detect.push_back(r.stats.detect_ms);
    deform.push_back(r.deform_ms);
    step.translation = -step.translation;
    step.angle = -step.angle;
  }
  state.counters["detect_median_ms"] = median(detect);
  state.counters["deform_median_ms"] = median(deform);
}

void preprocess(benchmark::State& state, const char* algorithm, std::int64_t threads = 1) {
  const Piercing& scene = Piercing::get(state.range(0) != 0);
  auto session = scene.session(true, false);
  double preprocess = 0.0;
  for (auto _ : state) {
    session->configure({{"algorithm", std::string(algorithm)}, {"threads", threads}});
    state.PauseTiming();
    preprocess = session->deform(DeformParams{}).stats.preprocess_ms;  // reports the reset's time
    state.ResumeTiming();
  }
  state.counters["preprocess_ms"] = preprocess;
}
void BM_Preprocess(benchmark::State& state) { preprocess(state, "robust"); }
void BM_PreprocessTemporal(benchmark::State& state) { preprocess(state, "temporal"); }
void BM_PreprocessThreads(benchmark::State& state) { preprocess(state, "robust", 2); }
void BM_PreprocessTemporalThreads(benchmark::State& state) { preprocess(state, "temporal", 2); }

// A detector configuration of BM_DetectRun / BM_DetectIdle: the algorithm and its hierarchy.
struct Config {
  const char* label;                 // printed in the benchmark's name
  CollisionAlgorithm algorithm;
  ZeroHierarchy zero;
  DeformableHierarchy deformable;
  bvh::UpdateMode update;            // of the deformable tree
};
constexpr bvh::UpdateMode kDefaultUpdate = bvh::BvhParams{}.update;
const Config kConfigs[] = {
    {"robust/none", CollisionAlgorithm::Robust, ZeroHierarchy::None, DeformableHierarchy::None, kDefaultUpdate},
    {"robust/aabb-aabb", CollisionAlgorithm::Robust, ZeroHierarchy::Aabb, DeformableHierarchy::Aabb, kDefaultUpdate},
    {"robust/aabb", CollisionAlgorithm::Robust, ZeroHierarchy::Aabb, DeformableHierarchy::None, kDefaultUpdate},
    {"robust/obb", CollisionAlgorithm::Robust, ZeroHierarchy::Obb, DeformableHierarchy::None, kDefaultUpdate},
    {"robust/sphere", CollisionAlgorithm::Robust, ZeroHierarchy::Sphere, DeformableHierarchy::None, kDefaultUpdate},
    {"robust/obb-aabb", CollisionAlgorithm::Robust, ZeroHierarchy::Obb, DeformableHierarchy::Aabb, kDefaultUpdate},
    {"robust/sphere-aabb", CollisionAlgorithm::Robust, ZeroHierarchy::Sphere, DeformableHierarchy::Aabb, kDefaultUpdate},
    {"robust/aabb-aabb/hybrid", CollisionAlgorithm::Robust, ZeroHierarchy::Aabb, DeformableHierarchy::Aabb,
     bvh::UpdateMode::Hybrid},
    {"robust/aabb-aabb/bottom_up", CollisionAlgorithm::Robust, ZeroHierarchy::Aabb, DeformableHierarchy::Aabb,
     bvh::UpdateMode::BottomUp},
    {"robust/aabb-aabb/top_down", CollisionAlgorithm::Robust, ZeroHierarchy::Aabb, DeformableHierarchy::Aabb,
     bvh::UpdateMode::TopDown},
    {"simple/none", CollisionAlgorithm::Simple, ZeroHierarchy::None, DeformableHierarchy::None, kDefaultUpdate},
    {"simple/aabb-aabb", CollisionAlgorithm::Simple, ZeroHierarchy::Aabb, DeformableHierarchy::Aabb, kDefaultUpdate},
    {"temporal/none", CollisionAlgorithm::Temporal, ZeroHierarchy::None, DeformableHierarchy::None, kDefaultUpdate},
    {"temporal/aabb-aabb", CollisionAlgorithm::Temporal, ZeroHierarchy::Aabb, DeformableHierarchy::Aabb,
     kDefaultUpdate},
};
constexpr int kConfigCount = static_cast<int>(sizeof(kConfigs) / sizeof(kConfigs[0]));

// The detector of the piercing scene on its own: positions, regions and a detector (one thread).
struct DetectorRun {
  Points positions, previous;
  std::vector<Region> regions;
  std::unique_ptr<CollisionDetector> detector;
  const Piercing& scene;

  explicit DetectorRun(const Config& config, int kind = 0) : scene(Piercing::get(kind)) {
    positions = scene.arrays.positions;
    previous = positions;
    regions.assign(static_cast<std::size_t>(positions.rows()), Region::Zero);
    for (SurfelId id : scene.one) regions[id] = Region::One;
    SessionSettings settings;
    settings.collision.algorithm = config.algorithm;
    settings.collision.threads = 1;
    settings.hierarchy.zero = config.zero;
    settings.hierarchy.deformable = config.deformable;
    settings.hierarchy.tree.update = config.update;
    detector = make_detector(settings);
    detector->reset(CollisionScene{positions, scene.arrays.normals, scene.arrays.radii, regions});
  }
  CollisionStats last;  // the last step's stats
  // Moves the ball by t (untimed by the caller), then detects; returns {thread CPU ms, re-tested}.
  std::pair<double, Index> step(const Vec3& t) {
    previous = positions;
    for (SurfelId id : scene.one) positions.row(static_cast<Index>(id)) += t.transpose();
    const double c0 = thread_cpu_ms();
    // The session's displacement bound for a translation (CollisionScene::displacement_bound).
    DeformParams move;
    move.translation = t;
    CollisionScene view{positions, scene.arrays.normals, scene.arrays.radii, regions};
    view.displacement_bound = displacement_bound(move);
    const CollisionResult r = detector->detect(view, previous);
    const double cpu = thread_cpu_ms() - c0;
    benchmark::DoNotOptimize(r.colliding.data());
    last = r.stats;
    return {cpu, r.stats.tested};
  }
};

// BM_DetectRun, BM_DetectRunTilted and BM_DetectRunTwoTilts (`kind` as Piercing's).
void detect_run(benchmark::State& state, int kind) {
  std::vector<double> cpu, nv, np, nu, queries;
  const Vec3 t = Piercing::get(kind).push();
  for (auto _ : state) {
    state.PauseTiming();
    DetectorRun run(kConfigs[state.range(0)], kind);
    for (int k = 0; k < kSteps; ++k) {
      state.ResumeTiming();
      // The move is timed too (a copy and 60k row updates, the same in A and B).
      cpu.push_back(run.step(t).first);
      state.PauseTiming();
      nv.push_back(static_cast<double>(run.last.nv));
      np.push_back(static_cast<double>(run.last.np));
      nu.push_back(static_cast<double>(run.last.nu));
      queries.push_back(static_cast<double>(run.last.queries));
    }
    state.ResumeTiming();
  }
  state.counters["detect_cpu_median_ms"] = median(cpu);
  // Medians over the steps of the broad phase's counts (0 without a hierarchy) and the queries.
  state.counters["nv_median"] = median(nv);
  state.counters["np_median"] = median(np);
  state.counters["nu_median"] = median(nu);
  state.counters["queries_median"] = median(queries);
  state.counters["detect_cpu_max_ms"] = *std::max_element(cpu.begin(), cpu.end());
}
void BM_DetectRun(benchmark::State& state) { detect_run(state, 0); }
void BM_DetectRunTilted(benchmark::State& state) { detect_run(state, 1); }
void BM_DetectRunTwoTilts(benchmark::State& state) { detect_run(state, 2); }

void BM_DetectIdle(benchmark::State& state) {
  const Config& config = kConfigs[state.range(0)];
  state.SetLabel(config.label);
  DetectorRun run(config);
  Vec3 t(1e-4, 0.0, 0.0);
  std::vector<double> cpu, nv, np, nu, queries;
  for (auto _ : state) {
    const auto [ms, tested] = run.step(t);
    // Robust: no point leaves its sphere (Simple tests its candidates each step, Temporal its own way).
    if (tested != 0 && config.algorithm == CollisionAlgorithm::Robust) throw std::runtime_error("idle step re-tested surfels");
    cpu.push_back(ms);
    nv.push_back(static_cast<double>(run.last.nv));
    np.push_back(static_cast<double>(run.last.np));
    nu.push_back(static_cast<double>(run.last.nu));
    queries.push_back(static_cast<double>(run.last.queries));
    t = -t;
  }
  state.counters["detect_cpu_median_ms"] = median(cpu);
  state.counters["nv_median"] = median(nv);
  state.counters["np_median"] = median(np);
  state.counters["nu_median"] = median(nu);
  state.counters["queries_median"] = median(queries);
}

BENCHMARK(BM_DetectRun)->DenseRange(0, 1)->Arg(10)->Arg(12)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_DetectRunTilted)->DenseRange(0, 1)->Arg(10)->Arg(12)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_DetectRunTwoTilts)->Arg(0)->Arg(12)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_DetectIdle)->DenseRange(0, kConfigCount - 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PiercingRun)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_IdleDrag)->DenseRange(0, 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IdleTurn)->DenseRange(1, 2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Preprocess)->DenseRange(0, 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PreprocessTemporal)->DenseRange(0, 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PreprocessThreads)->DenseRange(0, 1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PreprocessTemporalThreads)->DenseRange(0, 1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
