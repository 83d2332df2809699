// k-d tree benchmark: surfeledit::KdTree (our own tree, docs/algorithms.md §3) vs pcl::KdTreeFLANN<pcl::PointXYZ>,
// both on ONE thread, on the same points and the same query points.
//
// Normally run through bench/core/bench_kdtree.py, which writes the inputs and runs scipy and the
// Python binding beside this binary. By hand:
//   build/bench/surfeledit_bench_kdtree --points=P.f64 --queries=Q.f64
//       [--leaf-sweep=1,2,4,6,8,10,12,16,20,30,40,50] [--repetitions=5]
//       [--benchmark_out=out.json --benchmark_out_format=json]
// P.f64 / Q.f64: raw little-endian float64, x y z per point (file size = 24 bytes * count).
//
// Benchmarks (times in ms; items/s = queries per second for the knn ones):
//   build/ours/leaf:10   KdTree constructor (Morton sort + build into leaf order)
//   build/pcl            KdTreeFLANN::setInputCloud (float copy + FLANN single-tree build, leaf 15)
//   knn/ours/k:K         KdTree::knn(queries, K), batch API, threads = 1
//   knn/pcl/k:K          KdTreeFLANN::nearestKSearch per query, result vectors reused
//   single/ours/k:1      KdTree::nearest per query in the given order (the detectors' pattern)
//   sweep/{build,knn1,knn10}/leaf:L   ours with leaf size L
// Every benchmark repeats --repetitions times; the Python driver reads the median aggregate.
#include <benchmark/benchmark.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "surfeledit/core/kdtree.hpp"

namespace {

using surfeledit::KdTree;
using surfeledit::KdTreeParams;
using surfeledit::Points;

// Reads a raw float64 xyz file into #N by 3 points; exits with a message on a bad file.
Points read_points(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) {
    std::fprintf(stderr, "cannot open %s\n", path.c_str());
    std::exit(2);
  }
  const std::streamsize bytes = in.tellg();
  if (bytes <= 0 || bytes % (3 * sizeof(double)) != 0) {
    std::fprintf(stderr, "%s: size %lld is not a positive multiple of 24 bytes\n", path.c_str(),
                 static_cast<long long>(bytes));
    std::exit(2);
  }
  Points p(bytes / static_cast<std::streamsize>(3 * sizeof(double)), 3);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(p.data()), bytes);
  return p;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(const Points& p) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(static_cast<std::size_t>(p.rows()));
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    (*cloud)[i] = pcl::PointXYZ(static_cast<float>(p(i, 0)), static_cast<float>(p(i, 1)), static_cast<float>(p(i, 2)));
  }
  return cloud;
}

KdTreeParams one_thread(int leaf) {
  KdTreeParams params;
  params.leaf_size = leaf;
  params.threads = 1;  // batch queries on one thread
  return params;
}

// Inputs shared by all benchmarks (read once in main).
Points g_points, g_queries;
pcl::PointCloud<pcl::PointXYZ>::Ptr g_pcl_points, g_pcl_queries;

void ours_build(benchmark::State& state, int leaf) {
  for (auto _ : state) {
    KdTree tree(g_points, one_thread(leaf));
    benchmark::DoNotOptimize(tree.size());
  }
  state.counters["points"] = static_cast<double>(g_points.rows());
}

void ours_knn(benchmark::State& state, int leaf, int k) {
  const KdTree tree(g_points, one_thread(leaf));
  for (auto _ : state) {
    auto result = tree.knn(g_queries, k);
    benchmark::DoNotOptimize(result.indices.data());
  }
  state.SetItemsProcessed(state.iterations() * g_queries.rows());
}

// One KdTree::nearest call per query, in the file's order: what the detectors do (no batch sorting, no warm
// start), to separate the tree's own speed from the batch path's.
void ours_single(benchmark::State& state, int leaf) {
  const KdTree tree(g_points, one_thread(leaf));
  for (auto _ : state) {
    for (Eigen::Index q = 0; q < g_queries.rows(); ++q) {
      benchmark::DoNotOptimize(tree.nearest(g_queries.row(q).transpose()));
    }
  }
  state.SetItemsProcessed(state.iterations() * g_queries.rows());
}

void pcl_build(benchmark::State& state) {
  for (auto _ : state) {
    pcl::KdTreeFLANN<pcl::PointXYZ> tree;
    tree.setInputCloud(g_pcl_points);
    benchmark::ClobberMemory();
  }
  state.counters["points"] = static_cast<double>(g_pcl_points->size());
}

void pcl_knn(benchmark::State& state, int k) {
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(g_pcl_points);
  std::vector<int> indices(k);
  std::vector<float> dist2(k);
  for (auto _ : state) {
    for (const auto& q : *g_pcl_queries) {
      tree.nearestKSearch(q, k, indices, dist2);
      benchmark::DoNotOptimize(indices.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(g_pcl_queries->size()));
}

std::vector<int> parse_list(const std::string& s) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(std::atoi(item.c_str()));
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);  // consumes --benchmark_* flags
  std::string points_path, queries_path, sweep = "1,2,4,6,8,10,12,16,20,30,40,50";
  int repetitions = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) -> const char* {
      const std::string prefix = std::string(name) + "=";
      return a.rfind(prefix, 0) == 0 ? argv[i] + prefix.size() : nullptr;
    };
    if (const char* v = value("--points")) points_path = v;
    else if (const char* v2 = value("--queries")) queries_path = v2;
    else if (const char* v3 = value("--leaf-sweep")) sweep = v3;
    else if (const char* v4 = value("--repetitions")) repetitions = std::atoi(v4);
    else {
      std::fprintf(stderr, "unknown argument %s\n", argv[i]);
      return 2;
    }
  }
  if (points_path.empty() || queries_path.empty()) {
    std::fprintf(stderr, "usage: %s --points=P.f64 --queries=Q.f64 [--leaf-sweep=1,2,...] [--repetitions=N]\n", argv[0]);
    return 2;
  }
  g_points = read_points(points_path);
  g_queries = read_points(queries_path);
  g_pcl_points = to_pcl(g_points);
  g_pcl_queries = to_pcl(g_queries);
  benchmark::AddCustomContext("points", std::to_string(g_points.rows()));
  benchmark::AddCustomContext("queries", std::to_string(g_queries.rows()));

  auto setup = [&](benchmark::internal::Benchmark* b) {
    b->Unit(benchmark::kMillisecond)->Repetitions(repetitions)->ReportAggregatesOnly(true)->MinTime(0.2);
  };
  constexpr int kDefaultLeaf = 10;  // KdTreeParams' default, what the server uses
  setup(benchmark::RegisterBenchmark("build/ours/leaf:10", ours_build, kDefaultLeaf));
  setup(benchmark::RegisterBenchmark("build/pcl", pcl_build));
  for (int k : {1, 10}) {
    setup(benchmark::RegisterBenchmark(("knn/ours/k:" + std::to_string(k)).c_str(), ours_knn, kDefaultLeaf, k));
    setup(benchmark::RegisterBenchmark(("knn/pcl/k:" + std::to_string(k)).c_str(), pcl_knn, k));
  }
  setup(benchmark::RegisterBenchmark("single/ours/k:1", ours_single, kDefaultLeaf));
  for (int leaf : parse_list(sweep)) {
    const std::string l = std::to_string(leaf);
    setup(benchmark::RegisterBenchmark(("sweep/build/leaf:" + l).c_str(), ours_build, leaf));
    setup(benchmark::RegisterBenchmark(("sweep/knn1/leaf:" + l).c_str(), ours_knn, leaf, 1));
    setup(benchmark::RegisterBenchmark(("sweep/knn10/leaf:" + l).c_str(), ours_knn, leaf, 10));
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
