// The k-d tree's turned frame (KdTreeParams::align): axes along which a model's surfaces lie, for a model tilted
// against the world axes as a whole (a plate, a box, a wall scanned at an angle). The tree's cuts and cells are then
// along its surfaces, as they are for the same model upright (RESULTS §74).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Eigenvalues>

#include "kdtree_search.hpp"

namespace surfeledit::kd {

namespace {

// Points of the sample the candidates are compared on, and the bins of their coordinates along each axis.
constexpr std::size_t kSample = 1024;
constexpr int kBins = 256;
constexpr double kBetter = 1.25;  // the concentration a turned frame needs, over the world axes
// The angles tried about each candidate axis: a coarse pass over a quarter turn (a box repeats after one), then
// +-kFine steps of a fifth of the step before, twice (1 degree, then 0.2 degrees).
constexpr int kCoarse = 18;
constexpr double kStep = 0.5 * 3.14159265358979323846 / kCoarse;  // 5 degrees
constexpr int kFine = 4;

// The bin of a coordinate x (bins of width w, centred on 0).
int bin_of(double x, double w) { return std::clamp(static_cast<int>(x / w + 0.5 * kBins), 0, kBins - 1); }

// How concentrated the sample's coordinates are along the rows of `r`: the sum over the three axes of the squared
// counts of their bins (bin width `w`; every coordinate lies within +-w * kBins / 2). A surface along an axis puts
// its points in few bins of that axis; tilted, it spreads them.
double concentration(const std::vector<Eigen::Vector3d>& pts, const Eigen::Matrix3d& r, double w,
                     double* per_axis = nullptr) {
  std::uint32_t count[3][kBins] = {};
  for (const Eigen::Vector3d& p : pts) {
    const Eigen::Vector3d x = r * p;
    for (int d = 0; d < 3; ++d) ++count[d][bin_of(x[d], w)];
  }
  double sum = 0.0;
  for (int d = 0; d < 3; ++d) {
    double axis = 0.0;
    for (int b = 0; b < kBins; ++b) axis += static_cast<double>(count[d][b]) * count[d][b];
    if (per_axis) per_axis[d] = axis;
    sum += axis;
  }
  return sum;
}

// The floored volume of the box of `pts` along the rows of `r`.
double volume_along(const std::vector<Eigen::Vector3d>& pts, const Eigen::Matrix3d& r) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
  for (const Eigen::Vector3d& p : pts) {
    const Eigen::Vector3d x = r * p;
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double l[3] = {lo[0], lo[1], lo[2]}, h[3] = {hi[0], hi[1], hi[2]};
  return floored_volume(l, h);
}

// The next number of a SplitMix64 sequence.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// `base` turned by `angle` about its row k (the other two rows rotate in their plane).
Eigen::Matrix3d about(const Eigen::Matrix3d& base, int k, double angle) {
  const int i = (k + 1) % 3, j = (k + 2) % 3;
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix3d r = base;
  r.row(i) = c * base.row(i) + s * base.row(j);
  r.row(j) = -s * base.row(i) + c * base.row(j);
  return r;
}

// The best of `base` turned about its row k by `at` +- kFine steps of `step`, then of step / 5 around that, by
// `score` (larger is better).
template <class Score>
void refine(const Score& score_of, const Eigen::Matrix3d& base, int k, double step, double& at, double& score) {
  for (int round = 0; round < 2; ++round, step /= 5) {
    const double centre = at;
    for (int f = -kFine; f <= kFine; ++f) {
      const double v = score_of(about(base, k, centre + f * step));
      if (v > score) score = v, at = centre + f * step;
    }
  }
}

// The best of `base` turned about its row k over a quarter turn (coarse, then refined), by `score_of`.
template <class Score>
Eigen::Matrix3d best_about(const Score& score_of, const Eigen::Matrix3d& base, int k, double& score) {
  double at = 0.0;
  score = -HUGE_VAL;
  for (int a = 0; a < kCoarse; ++a) {
    const double v = score_of(about(base, k, a * kStep));
    if (v > score) score = v, at = a * kStep;
  }
  refine(score_of, base, k, kStep / 5, at, score);
  return about(base, k, at);
}

}  // namespace

double floored_volume(const double lo[3], const double hi[3]) {
  double ext[3], longest = 0.0;
  for (int d = 0; d < 3; ++d) longest = std::max(longest, ext[d] = hi[d] - lo[d]);
  double v = 1.0;
  for (int d = 0; d < 3; ++d) v *= std::max(ext[d], 1e-3 * longest);
  return v;
}

bool choose_turn(const double* points, const std::vector<std::uint32_t>& rows, const double* origin,
                 double turn[3][3]) {
  const std::size_t n = rows.size();
  if (n < 4) return false;
  std::vector<Eigen::Vector3d> sample;
  sample.reserve(kSample + 1);
  // Drawn by a fixed-seed generator, not strided: a strided sample of a lattice lines up along oblique rows.
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double reach = 0.0;
  std::uint64_t state = 0x9e3779b97f4a7c15ull;
  for (std::size_t k = 0; k < std::min(n, kSample); ++k) {
    const std::size_t i = n <= kSample ? k : static_cast<std::size_t>(splitmix64(state) % n);
    const double* p = points + 3 * static_cast<std::size_t>(rows[i]);
    sample.emplace_back(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]);
    cov.noalias() += sample.back() * sample.back().transpose();
    reach = std::max(reach, sample.back().norm());
  }
  if (!(reach > 0.0) || !std::isfinite(reach)) return false;
  const double w = 2.0 * reach * (1.0 + 1e-9) / kBins;
  // The surfaces' directions by concentration: the world axes, and the sample's principal axes turned about each of
  // their own axes (a flat part's normal is one of them); the best one refined about each of its axes (the principal
  // axes of a sample of a plate with more on it are only about its normal).
  const auto concentrated = [&](const Eigen::Matrix3d& r) { return concentration(sample, r, w); };
  const Eigen::Matrix3d world = Eigen::Matrix3d::Identity();
  const double world_score = concentrated(world);
  Eigen::Matrix3d best = world;
  double best_score = world_score;
  const Eigen::Matrix3d principal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().transpose();
  if (principal.allFinite()) {
    for (int k = 0; k < 3; ++k) {
      double score;
      const Eigen::Matrix3d r = best_about(concentrated, principal, k, score);
      if (score > best_score) best_score = score, best = r;
    }
  }
  // Clearly more concentrated than along the world axes (a sample's noise moves the score by a few percent).
  if (!(best_score > kBetter * world_score)) return false;
  for (int k = 0; k < 3; ++k) {
    double at = 0.0, score = best_score;
    refine(concentrated, best, k, kStep / 5, at, score);
    if (score > best_score) best_score = score, best = about(best, k, at);
  }
  // The turn about the most concentrated axis (a flat part's normal) by the smallest box: on a sampled lattice the
  // concentration of the other two axes follows its rows (diagonals alias into fewer bins), the box does not.
  double per_axis[3];
  concentration(sample, best, w, per_axis);
  const int normal = static_cast<int>(std::max_element(per_axis, per_axis + 3) - per_axis);
  // That normal exactly: the smallest principal axis of every point within a bin of the sample's fullest bin along it
  // (the flat part itself; the sample's bins only place it to about a tenth of a degree, and that costs the searches
  // a fifth of their time on a tilted plate, RESULTS §74).
  const Eigen::Vector3d along = best.row(normal).transpose();
  std::vector<std::uint32_t> bins(kBins, 0);
  for (const Eigen::Vector3d& p : sample) ++bins[static_cast<std::size_t>(bin_of(along.dot(p), w))];
  const double fullest = static_cast<double>(std::max_element(bins.begin(), bins.end()) - bins.begin());
  const double centre = (fullest + 0.5 - 0.5 * kBins) * w;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d moments = Eigen::Matrix3d::Zero();
  double count = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double* p = points + 3 * static_cast<std::size_t>(rows[i]);
    const Eigen::Vector3d t(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]);
    if (std::abs(along.dot(t) - centre) > w) continue;
    sum += t;
    moments.noalias() += t * t.transpose();
    count += 1.0;
  }
  if (count >= 3.0) {
    const Eigen::Matrix3d flat = moments - sum * sum.transpose() / count;
    const Eigen::Vector3d m = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(flat).eigenvectors().col(0);
    if (m.allFinite() && std::abs(m.dot(along)) > std::cos(2.0 * kStep)) {
      // The other two rows: the old ones made orthogonal to it (Gram-Schmidt).
      const int i = (normal + 1) % 3, j = (normal + 2) % 3;
      best.row(normal) = m.transpose();
      best.row(i) = (best.row(i) - best.row(i).dot(best.row(normal)) * best.row(normal)).normalized();
      best.row(j) = best.row(normal).cross(best.row(i));
      if (!best.allFinite()) return false;
    }
  }
  double small;
  best = best_about([&](const Eigen::Matrix3d& r) { return -volume_along(sample, r); }, best, normal, small);
  for (int i = 0; i < 3; ++i)
    for (int d = 0; d < 3; ++d) turn[i][d] = best(i, d);
  return true;
}

}  // namespace surfeledit::kd
