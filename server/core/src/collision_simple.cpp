// Simple and Improved Simple Algo (§4.1, §4.2 of docs/algorithms.md; thesis Code 6.1): the zero-region
// reference of the Simple and Temporal kernels, and Improved's spatial-coherence sweep.
#include <cmath>
#include <memory>
#include <optional>

#include "at_once.hpp"
#include "collision/improved_sweep.hpp"

namespace surfeledit::detail {

void ZeroSetKernel::reset(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows,
                          int threads) {
  ZeroSet zero;
  // The boundary marks search a tree over the whole model, which does not depend on the zero set's: with threads > 1
  // on a large model the two are built at once (at_once.hpp; the same trees as one after the other).
  const bool marks = params_.boundary && !deformable.empty();
  std::optional<KdTree> whole;
  at_once(
      marks && at_once_pays(threads, scene.regions.size()),
      [&] { zero.build(scene, zero_rows, params_.knn_eps, zero_cells_); },
      [&] {
        if (marks) whole.emplace(scene.positions, ZeroSet::whole_tree_params(threads));
      });
  reset_nearest_ = KnnResult();
  if (marks) {  // (no deformable row: nothing marked, build() left every mark 0)
    zero.mark_boundary(scene, deformable, *whole, params_.boundary_n, params_.boundary_i, threads,
                       keep_reset_nearest_ ? &reset_nearest_ : nullptr);
  }
  zero_ = std::move(zero);
}

Tally ImprovedSweep::run(const SimpleKernel& kernel, const IndexList& rows, RowStates<SimpleKernel::State>& states,
                         const CollisionScene& scene, const Points& previous,
                         const std::vector<std::uint8_t>* candidate, int /*threads*/, std::vector<std::uint8_t>& hit) {
  if (candidate) throw Error(ErrorCode::Internal, "algorithm", "improved cannot run on candidates only");
  std::vector<std::uint8_t> settled(states.size(), 0);
  std::unique_ptr<KdTree> moving;  // per-step tree over the deformable positions, built on first need
  IndexList hits;
  std::vector<double> hit_dist2;
  double sum_dist2 = 0.0;
  Tally tally;
  for (Index r : rows) {
    if (settled[r]) continue;
    const TestPoint pt = row_point(scene, previous, r);
    const Vec3& p1 = pt.p;
    const SimpleTest t = kernel.test(states[r], pt);
    ++tally.queries;
    settled[r] = 1;
    ++tally.tested;
    sum_dist2 += t.dist2;
    if (!(t.dist2 > mean_dist2_)) continue;
    // No zero surfel lies strictly inside B(p1, |d|): every deformable surfel in it shares s1's state.
    if (!moving) moving = std::make_unique<KdTree>(scene.positions, rows, nearest_tree_params(0.0));
    const double reach = std::sqrt(t.dist2);
    moving->radius(p1, reach * (1.0 + 1e-9) + 1e-300, hits, hit_dist2);
    for (Index j : hits) {
      if (settled[j]) continue;
      const double e2 = (row3(scene.positions, j) - p1).squaredNorm();
      if (!(e2 < t.dist2)) continue;  // strictly inside, measured in world coordinates
      settled[j] = 1;
      states[j].hit = t.state;
      states[j].depth = reach - std::sqrt(e2);
    }
  }
  for (std::size_t q = 0; q < rows.size(); ++q) hit[q] = states[rows[q]].colliding();
  mean_dist2_ = tally.tested > 0 ? sum_dist2 / tally.tested : 0.0;
  return tally;
}

}  // namespace surfeledit::detail
