// Robust Algo (§4.4 of docs/algorithms.md, thesis §6.3): the original model's snapshot of the Robust
// kernel (collision/robust_kernel.hpp).
#include "collision/robust_kernel.hpp"

namespace surfeledit::detail {

void RobustKernel::reset(const CollisionScene& scene, const IndexList&, const IndexList& zero_rows, int) {
  if (zero_rows.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region is empty");
  const Index rows = static_cast<Index>(scene.regions.size());
  Snapshot orig;
  orig.positions = scene.positions;
  orig.normals = scene.normals;
  orig.radii = scene.radii;
  orig.zero.resize(static_cast<std::size_t>(rows));
  for (Index r = 0; r < rows; ++r) orig.zero[r] = scene.regions[r] == Region::Zero;
  orig.alive.assign(static_cast<std::size_t>(rows), 1);
  orig.tree = original_tree(orig.positions, orig.alive, params_.knn_eps);
  orig_ = std::move(orig);
  orig_of_row_ = IndexList();  // the identity
  build_inside();
}

void RobustKernel::build_inside() {
  inside_.reset();
  if (params_.inside == InsideMode::Nearest && !params_.swept) return;
  IndexList zero;
  for (std::size_t o = 0; o < orig_.zero.size(); ++o)
    if (orig_.zero[o] && orig_.alive[o]) zero.push_back(static_cast<Index>(o));
  const Index n = static_cast<Index>(zero.size());
  Points pos(n, 3), nrm(n, 3);
  Values rad(n);
  for (Index q = 0; q < n; ++q) {
    pos.row(q) = orig_.positions.row(zero[q]);
    nrm.row(q) = orig_.normals.row(zero[q]);
    rad[q] = orig_.radii[zero[q]];
  }
  auto tree = std::make_shared<const KdTree>(pos, nearest_tree_params(params_.knn_eps));
  inside_ = std::make_shared<const InsideModel>(pos, nrm, rad, std::move(tree), params_);
}

void RobustKernel::seed(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows,
                        int threads, RowStates<State>& states) const {
  const KdTree zero_tree(scene.positions, zero_rows, nearest_tree_params(params_.knn_eps));
  seed_states(
      *this, scene.positions, deformable, threads,
      [&](const Vec3& p) {
        const Index k = zero_tree.nearest(p);
        return NearestZero{(p - row3(scene.positions, k)).squaredNorm(), scene.radii[k]};
      },
      states);
}

void RobustKernel::on_removed(const std::vector<bool>& keep, const IndexList&) {
  bool zero_removed = false;
  for (std::size_t r = 0; r < keep.size(); ++r) {
    const Index o = orig_of(static_cast<Index>(r));
    if (!keep[r] && o >= 0 && orig_.zero[o]) {
      orig_.alive[o] = 0;
      zero_removed = true;
    }
  }
  if (zero_removed) {
    orig_.tree = original_tree(orig_.positions, orig_.alive, params_.knn_eps);
    build_inside();
  }
  spell_out_rows();
  compact(orig_of_row_, keep);
}

bool RobustKernel::on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const IndexList& deformable,
                                  RowStates<State>& states, int threads) {
  if (inside_ || !orig_.tree) return false;
  for (Index r : rows) {
    if (r < 0 || static_cast<std::size_t>(r) >= rows_now()) return false;
    const Index o = orig_of(r);
    if (o < 0 || !orig_.zero[o] || !orig_.alive[o]) return false;  // not a zero surfel of the snapshot
  }
  if (rows.empty()) return true;
  // The points to test at their next step. One whose inside state is still to be re-derived at its old
  // position gets it now, against the rigid part where it was: the next test then counts the change
  // when the other tool's part came over it.
  double reach = 0.0;
  for (Index r : rows) reach = std::max(reach, (row3(orig_.positions, orig_of(r)) - row3(scene.positions, r)).norm());
  const IndexList hit = rows_near_moved<true>(scene, rows, reach, deformable, states, threads);
  for (Index r : hit) {
    State& s = states[r];
    if (!(s.flags & kFirstUpdate)) continue;
    const Index k = orig_.tree->nearest(s.old_position);
    s.flags &= static_cast<std::uint8_t>(~kFirstUpdate);
    set_inside(s, (s.old_position - row3(orig_.positions, k)).dot(row3(orig_.normals, k)) < params_.threshold);
  }
  for (Index r : rows) {
    const Index o = orig_of(r);
    orig_.positions.row(o) = scene.positions.row(r);
    orig_.normals.row(o) = scene.normals.row(r);
    orig_.radii[o] = scene.radii[r];
  }
  // A new tree (clones in history images share the old one with their own, older snapshot).
  orig_.tree = original_tree(orig_.positions, orig_.alive, params_.knn_eps);
  for (Index r : hit) states[r].sphere.rho2 = 0.0;
  return true;
}

std::shared_ptr<const KdTree> RobustKernel::original_tree(const Points& positions, const std::vector<std::uint8_t>& alive,
                                                          double eps) {
  KdTreeParams params = nearest_tree_params(eps);
  params.leaf_size = kOriginalLeafSize;
  if (std::all_of(alive.begin(), alive.end(), [](std::uint8_t a) { return a != 0; })) {
    return std::make_shared<const KdTree>(positions, params);
  }
  IndexList rows;
  for (std::size_t o = 0; o < alive.size(); ++o)
    if (alive[o]) rows.push_back(static_cast<Index>(o));
  return std::make_shared<const KdTree>(positions, rows, params);
}

std::size_t RobustKernel::memory_bytes() const {
  return static_cast<std::size_t>(orig_.positions.size() + orig_.normals.size() + orig_.radii.size()) * sizeof(double) +
         orig_.zero.capacity() + orig_.alive.capacity() + (orig_.tree ? orig_.tree->memory_bytes() : 0) +
         orig_of_row_.capacity() * sizeof(Index) + (inside_ ? inside_->memory_bytes() : 0);
}

}  // namespace surfeledit::detail
