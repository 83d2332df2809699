// bench_host: what this machine gives one thread right now, so that a figure elsewhere in bench/ can be read
// against the host it ran on (bench/RESULTS.md §89). Hosts of one name have given the same binary figures 2-2.5x
// apart from one session to the next (§89: probably different hardware); these probes say which of the machine's
// parts differ: the core's clock (a dependent chain of integer multiplies), the latency of each cache level and of
// memory (a dependent walk of a random cycle of cache lines, each working set its own benchmark), and the bandwidth
// of a streaming read. No surfeledit code is involved.
//
//   taskset -c 1 build/bench/surfeledit_bench_host --benchmark_counters_tabular=true
//
// Counters: `ns_per_op` (chain: one multiply-add; walk: one cache line reached), `gbytes` per second (stream). The
// context printed first names the CPU (vendor, family, model, AVX-512 or not).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace {

// A chain of 64-bit multiply-adds, each waiting on the last: its time per link is the multiplier's latency in
// cycles (3-4 on current x86) over the core's clock, with no memory involved.
void BM_Chain(benchmark::State& state) {
  constexpr std::int64_t kLinks = 1 << 24;
  std::uint64_t x = 0x9E3779B97F4A7C15ull;
  for (auto _ : state) {
    for (std::int64_t i = 0; i < kLinks; ++i) x = x * 6364136223846793005ull + 1442695040888963407ull;
    benchmark::DoNotOptimize(x);
  }
  state.counters["ns_per_op"] = benchmark::Counter(static_cast<double>(state.iterations() * kLinks),
                                                   benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Chain)->Unit(benchmark::kMillisecond)->MinTime(0.3);

// One cache line: the index of the next line in a random cycle over the working set, padded to 64 bytes.
struct alignas(64) Line {
  std::uint32_t next;
};

// A dependent walk over a random cycle of state.range(0) KiB of cache lines (fixed seed): every load waits for
// the last, and the hardware prefetcher cannot guess the next, so its time per line is that level's latency.
void BM_Walk(benchmark::State& state) {
  const std::size_t lines = static_cast<std::size_t>(state.range(0)) * 1024 / sizeof(Line);
  std::vector<std::uint32_t> order(lines);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin() + 1, order.end(), std::mt19937_64(1));
  std::vector<Line> ring(lines);
  for (std::size_t i = 0; i < lines; ++i) ring[order[i]].next = order[(i + 1) % lines];
  constexpr std::int64_t kSteps = 1 << 22;
  std::uint32_t at = 0;
  for (auto _ : state) {
    for (std::int64_t i = 0; i < kSteps; ++i) at = ring[at].next;
    benchmark::DoNotOptimize(at);
  }
  state.counters["ns_per_op"] = benchmark::Counter(static_cast<double>(state.iterations() * kSteps),
                                                   benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
// 16 KiB (L1), 256 KiB (L2), 4 MiB (L3 on most hosts), 128 MiB (memory).
BENCHMARK(BM_Walk)->Arg(16)->Arg(256)->Arg(4 << 10)->Arg(128 << 10)->Unit(benchmark::kMillisecond)->MinTime(0.3);

// A streaming sum over 128 MiB of doubles: the memory bandwidth one thread gets.
void BM_Stream(benchmark::State& state) {
  std::vector<double> data(std::size_t{16} << 20, 1.0);
  for (auto _ : state) {
    double sum[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < data.size(); i += 4)
      for (int k = 0; k < 4; ++k) sum[k] += data[i + k];
    benchmark::DoNotOptimize(sum);
  }
  state.counters["gbytes"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(data.size() * sizeof(double)) / 1e9,
      benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Stream)->Unit(benchmark::kMillisecond)->MinTime(0.3);

// The CPU's vendor, family and model and whether it has AVX-512 (/proc/cpuinfo's first processor), for the
// benchmark's context: hosts of one name have differed in these.
void add_cpu_context() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, family, model, vendor;
  bool avx512 = false;
  while (std::getline(in, line)) {
    const auto value = [&] { return line.substr(line.find(':') + 2); };
    if (line.rfind("vendor_id", 0) == 0 && vendor.empty()) vendor = value();
    if (line.rfind("cpu family", 0) == 0 && family.empty()) family = value();
    if (line.rfind("model\t", 0) == 0 && model.empty()) model = value();
    if (line.rfind("flags", 0) == 0) {
      avx512 = line.find(" avx512f") != std::string::npos;
      break;
    }
  }
  benchmark::AddCustomContext("cpu", vendor + " family " + family + " model " + model +
                                         (avx512 ? ", AVX-512" : ", no AVX-512"));
}

}  // namespace

int main(int argc, char** argv) {
  add_cpu_context();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
