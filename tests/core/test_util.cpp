// util.hpp: compaction of vectors, #P by 3 arrays and #P values against a copy-if reference,
// remap_rows against counting, resolve_threads.
#include <gtest/gtest.h>

#include <omp.h>

#include <random>

#include "surfeledit/core/util.hpp"

namespace surfeledit {
namespace {

std::vector<bool> random_keep(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution b(0.4);
  std::vector<bool> keep(n);
  for (std::size_t i = 0; i < n; ++i) keep[i] = b(rng);
  return keep;
}

TEST(Util, CompactKeepsFlaggedEntriesInOrder) {
  const std::size_t n = 1000;
  const std::vector<bool> keep = random_keep(n, 3);
  std::vector<int> v(n);
  Points p(static_cast<Eigen::Index>(n), 3);
  Values r(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    v[i] = static_cast<int>(i) * 7;
    p.row(static_cast<Eigen::Index>(i)) << double(i), -double(i), 0.5 * double(i);
    r[static_cast<Eigen::Index>(i)] = 1.0 + double(i);
  }
  std::vector<int> want;
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i]) want.push_back(static_cast<int>(i) * 7);

  compact(v, keep);
  compact(p, keep);
  compact(r, keep);
  EXPECT_EQ(v, want);
  ASSERT_EQ(p.rows(), static_cast<Eigen::Index>(want.size()));
  ASSERT_EQ(r.size(), static_cast<Eigen::Index>(want.size()));
  for (std::size_t k = 0; k < want.size(); ++k) {
    const double i = want[k] / 7;
    const auto row = static_cast<Eigen::Index>(k);
    EXPECT_EQ(p(row, 0), i);
    EXPECT_EQ(p(row, 1), -i);
    EXPECT_EQ(p(row, 2), 0.5 * i);
    EXPECT_EQ(r[row], 1.0 + i);
  }
}

TEST(Util, CompactAllAndNothing) {
  Points p = Points::Random(5, 3);
  const Points before = p;
  compact(p, std::vector<bool>(5, true));
  EXPECT_EQ(p, before);
  compact(p, std::vector<bool>(5, false));
  EXPECT_EQ(p.rows(), 0);
  EXPECT_EQ(p.cols(), 3);
}

TEST(Util, RemapRowsCountsKeptRowsBefore) {
  const std::vector<bool> keep = random_keep(500, 4);
  const IndexList map = remap_rows(keep);
  ASSERT_EQ(map.size(), keep.size());
  for (std::size_t i = 0; i < keep.size(); ++i) {
    Index before = 0;
    for (std::size_t j = 0; j < i; ++j) before += keep[j] ? 1 : 0;
    EXPECT_EQ(map[i], keep[i] ? before : -1) << "row " << i;
  }
  EXPECT_TRUE(remap_rows({}).empty());
}

TEST(Util, ResolveThreads) {
  EXPECT_EQ(resolve_threads(3), 3);
  EXPECT_EQ(resolve_threads(0), omp_get_max_threads());
  EXPECT_EQ(resolve_threads(-1), omp_get_max_threads());
}

}  // namespace
}  // namespace surfeledit
