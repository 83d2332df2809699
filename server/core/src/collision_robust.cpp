// Robust Algo (§4.4 of docs/algorithms.md, thesis §6.3): the original model of the Robust kernel
// (collision/robust_kernel.hpp): the deformable rows' values at reset, the zero rows read from the model.
#include "collision/robust_kernel.hpp"

namespace surfeledit::detail {

template <bool kHeld>
void RobustKernelT<kHeld>::reset(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows, int) {
  if (zero_rows.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region is empty");
  const Index rows = static_cast<Index>(scene.regions.size());
  Original orig;
  orig.deformable.assign(rows, deformable);
  const Index n = static_cast<Index>(deformable.size());
  orig.positions.resize(n, 3);
  orig.normals.resize(n, 3);
  orig.radii.resize(n);
  for (Index d = 0; d < n; ++d) {
    const Index r = deformable[static_cast<std::size_t>(d)];
    orig.positions.row(d) = scene.positions.row(r);
    orig.normals.row(d) = scene.normals.row(r);
    orig.radii[d] = scene.radii[r];
  }
  orig_ = std::move(orig);
  orig_of_row_ = IndexList();  // the identity
  row_of_orig_ = IndexList();
  orig_.tree = original_tree(scene.positions);  // the model now is the original model
  bind_model(scene);
  pending_inside_ = false;
  build_inside();
}

template <bool kHeld>
void RobustKernelT<kHeld>::bind(const CollisionScene& scene) {
  if (static_cast<std::size_t>(scene.positions.rows()) != rows_now()) {
    throw Error(ErrorCode::Internal, "detect", "row count differs from the detector's");
  }
  bind_model(scene);
  if (!orig_.tree) orig_.tree = original_tree(original_points(scene));
  if (pending_inside_) {
    build_inside();
    pending_inside_ = false;
  }
}

template <bool kHeld>
void RobustKernelT<kHeld>::bind_model(const CollisionScene& scene) {
  model_positions_ = scene.positions.data();
  model_normals_ = scene.normals.data();
  model_radii_ = scene.radii.data();
}

template <bool kHeld>
Points RobustKernelT<kHeld>::original_points(const CollisionScene& scene, const IndexList* moved, const RigidRows* before) const {
  const Index n = original_rows();
  Points out(n, 3);
  for (Index o = 0; o < n; ++o) {
    if (orig_.deformable.test(o)) {
      out.row(o) = orig_.positions.row(orig_.deformable.rank(o));
    } else {
      const Index r = row_of(o);
      if (r >= 0) out.row(o) = scene.positions.row(r);
      else out.row(o).setZero();  // removed: not in the tree
    }
  }
  if (moved) {
    for (std::size_t j = 0; j < moved->size(); ++j) out.row(orig_of((*moved)[j])) = before->positions.row(static_cast<Eigen::Index>(j));
  }
  return out;
}

template <bool kHeld>
void RobustKernelT<kHeld>::build_inside() {
  inside_.reset();
  if (!with_inside()) return;
  // Built at reset and at the first bind after a removal of zero rows, from the bound model.
  IndexList zero;
  for (Index o = 0; o < original_rows(); ++o)
    if (!orig_.deformable.test(o) && alive(o)) zero.push_back(o);
  const Index n = static_cast<Index>(zero.size());
  Points pos(n, 3), nrm(n, 3);
  Values rad(n);
  for (Index q = 0; q < n; ++q) {
    const Ref k = ref(zero[q]);
    pos.row(q) = k.p.transpose();
    nrm.row(q) = k.n.transpose();
    rad[q] = k.radius;
  }
  auto tree = std::make_shared<const KdTree>(pos, nearest_tree_params(params_.knn_eps));
  inside_ = std::make_shared<const InsideModel>(pos, nrm, rad, std::move(tree), params_);
}

template <bool kHeld>
void RobustKernelT<kHeld>::seed(const CollisionScene& scene, const IndexList& deformable, const IndexList& zero_rows,
                        int threads, RowStates<State>& states) const {
  KdTreeParams params = nearest_tree_params(params_.knn_eps);
  params.leaf_size = kSeedLeafSize;
  params.frames = true;
  const KdTree zero_tree(scene.positions, zero_rows, params);
  seed_states(*this, scene.positions, deformable, threads, zero_tree, scene.positions, scene.radii, states);
}

template <bool kHeld>
void RobustKernelT<kHeld>::on_removed(const std::vector<bool>& keep, const IndexList&) {
  bool zero_removed = false;
  for (std::size_t r = 0; r < keep.size(); ++r) {
    const Index o = orig_of(static_cast<Index>(r));
    if (!keep[r] && o >= 0 && !orig_.deformable.test(o)) {
      if (orig_.alive.empty()) orig_.alive.assign(static_cast<std::size_t>(original_rows()), 1);
      orig_.alive[static_cast<std::size_t>(o)] = 0;
      zero_removed = true;
    }
  }
  spell_out_rows();
  compact(orig_of_row_, keep);
  // The original rows' model rows now (a removed deformable row stays in the original model, from the copy).
  row_of_orig_.assign(static_cast<std::size_t>(original_rows()), -1);
  for (std::size_t r = 0; r < orig_of_row_.size(); ++r)
    if (orig_of_row_[r] >= 0) row_of_orig_[static_cast<std::size_t>(orig_of_row_[r])] = static_cast<Index>(r);
  if (zero_removed) {
    // The tree over the alive rows (and the inside model over the alive zero rows) are built at the next
    // bind, from the model with its rows as they are then.
    orig_.tree.reset();
    if (inside_) {
      inside_.reset();
      pending_inside_ = true;
    }
  }
}

template <bool kHeld>
bool RobustKernelT<kHeld>::on_rigid_moved(const CollisionScene& scene, const IndexList& rows, const RigidRows& before,
                                  const IndexList& deformable, RowStates<State>& states, int threads) {
  if (with_inside()) return false;
  if (static_cast<std::size_t>(scene.positions.rows()) != rows_now()) return false;
  for (Index r : rows) {
    if (r < 0 || static_cast<std::size_t>(r) >= rows_now()) return false;
    const Index o = orig_of(r);
    if (o < 0 || orig_.deformable.test(o) || !alive(o)) return false;  // not a zero surfel of the original model
  }
  if (rows.empty()) return true;
  // The rigid part as this detector saw it: the old tree (built now when there is none), the model but the
  // moved rows at `before`.
  if (!orig_.tree) orig_.tree = original_tree(original_points(scene, &rows, &before));
  bind_model(scene);
  // The points to test at their next step. One whose inside state is still to be re-derived at its old
  // position gets it now, against the rigid part where it was: the next test then counts the change
  // when the other tool's part came over it.
  double reach = 0.0;
  for (std::size_t j = 0; j < rows.size(); ++j) {
    const Index r = rows[j];
    reach = std::max(reach, (before.positions.row(static_cast<Eigen::Index>(j)) - scene.positions.row(r)).norm());
  }
  const IndexList hit = rows_near_moved<true>(scene, rows, reach, deformable, states, threads);
  for (Index r : hit) {
    State& s = states[r];
    if (!(s.flags & kFirstUpdate)) continue;
    const Vec3 p0 = old(s, scene.positions.data() + 3 * static_cast<std::ptrdiff_t>(r));  // its position now, or held
    const Index o = orig_.tree->nearest(p0);
    Ref k = ref(o);
    if (k.zero) {  // a moved row: where it was
      const auto it = std::lower_bound(rows.begin(), rows.end(), row_of(o));
      if (it != rows.end() && *it == row_of(o)) {
        const Eigen::Index j = it - rows.begin();
        k.p = row3(before.positions, static_cast<Index>(j));
        k.n = row3(before.normals, static_cast<Index>(j));
      }
    }
    s.flags &= static_cast<std::uint8_t>(~kFirstUpdate);
    set_inside(s, (p0 - k.p).dot(k.n) < params_.threshold);
  }
  // A new tree over the rigid part where it is now (clones in history images share the old one, and read
  // the model as it was when they are brought back with it).
  orig_.tree = original_tree(original_points(scene));
  for (Index r : hit) states[r].sphere.rho2 = 0.0;
  return true;
}

template <bool kHeld>
std::shared_ptr<const KdTree> RobustKernelT<kHeld>::original_tree(const Points& positions) {
  KdTreeParams params = nearest_tree_params(params_.knn_eps);
  params.leaf_size = kNearestLeafSize;
  params.frames = true;
  params.cells = true;  // each test's search starts at the leaf of the point's last nearest (State::leaf)
  std::shared_ptr<const KdTree> tree;
  if (orig_.alive.empty() || std::all_of(orig_.alive.begin(), orig_.alive.end(), [](std::uint8_t a) { return a != 0; })) {
    tree = std::make_shared<const KdTree>(positions, params);
  } else {
    IndexList rows;
    for (std::size_t o = 0; o < orig_.alive.size(); ++o)
      if (orig_.alive[o]) rows.push_back(static_cast<Index>(o));
    tree = std::make_shared<const KdTree>(positions, rows, params);
  }
  tree_bytes_ = tree->memory_bytes();
  return tree;
}

template <bool kHeld>
std::size_t RobustKernelT<kHeld>::memory_bytes() const {
  return static_cast<std::size_t>(orig_.positions.size() + orig_.normals.size() + orig_.radii.size()) * sizeof(double) +
         orig_.deformable.memory_bytes() + orig_.alive.capacity() + (orig_.tree ? orig_.tree->memory_bytes() : tree_bytes_) +
         (orig_of_row_.capacity() + row_of_orig_.capacity()) * sizeof(Index) + (inside_ ? inside_->memory_bytes() : 0);
}

template class RobustKernelT<false>;
template class RobustKernelT<true>;

}  // namespace surfeledit::detail
