// Snapshots of the collision detectors (detector_snapshot.hpp): params, the row detectors' kernels.
// The k-d trees are not written: a tree's build is a deterministic function of its points, their
// order and its params (kdtree_build.cpp: sequential, no randomness), so the tree built again from
// the saved points answers every query as the saved one did (tests/core/test_session_snapshot.cpp
// checks this against the tree of the live detector).
#include <limits>
#include <sstream>

#include "collision/kernel_snapshot.hpp"
#include "collision/row_detector.hpp"
#include "surfeledit/core/detector_snapshot.hpp"

namespace surfeledit {

bool CollisionDetector::snapshottable() const { return false; }

void CollisionDetector::save_state(SnapshotWriter&) const {
  throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
}

void CollisionDetector::load_state(SnapshotReader&) {
  throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
}

void CollisionDetector::save_image_state(SnapshotWriter&, const DetectorImage&) const {
  throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
}

std::shared_ptr<const DetectorImage> CollisionDetector::load_image_state(SnapshotReader&) const {
  throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
}

void save_params(SnapshotWriter& out, const CollisionParams& p) {
  out.u8(static_cast<std::uint8_t>(p.algorithm));
  out.f64(p.threshold);
  out.boolean(p.boundary);
  out.i64(p.boundary_n);
  out.i64(p.boundary_i);
  out.boolean(p.step_bound);
  out.f64(p.sphere_margin);
  out.i64(p.threads);
  out.f64(p.knn_eps);
  out.u8(static_cast<std::uint8_t>(p.inside));
  out.f64(p.winding_beta);
  out.i64(p.vote_k);
  out.boolean(p.swept);
}

namespace {
int get_int(SnapshotReader& in, const char* what) {
  const std::int64_t v = in.i64(what);
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) in.fail(what, "out of range");
  return static_cast<int>(v);
}
}  // namespace

CollisionParams load_params(SnapshotReader& in) {
  CollisionParams p;
  const std::uint8_t algorithm = in.u8("algorithm");
  if (algorithm > static_cast<std::uint8_t>(CollisionAlgorithm::Robust)) in.fail("algorithm", "unknown value");
  p.algorithm = static_cast<CollisionAlgorithm>(algorithm);
  p.threshold = in.f64("threshold");
  p.boundary = in.boolean("boundary");
  p.boundary_n = get_int(in, "boundary_n");
  p.boundary_i = get_int(in, "boundary_i");
  p.step_bound = in.boolean("step_bound");
  p.sphere_margin = in.f64("sphere_margin");
  p.threads = get_int(in, "threads");
  p.knn_eps = in.f64("knn_eps");
  const std::uint8_t inside = in.u8("inside");
  if (inside > static_cast<std::uint8_t>(InsideMode::Vote)) in.fail("inside", "unknown value");
  p.inside = static_cast<InsideMode>(inside);
  p.winding_beta = in.f64("winding_beta");
  p.vote_k = get_int(in, "vote_k");
  p.swept = in.boolean("swept");
  try {
    validate(p);
  } catch (const Error& e) {
    in.fail("collision params", e.what());
  }
  return p;
}

void save_detector(SnapshotWriter& out, const CollisionDetector& detector) {
  if (!detector.snapshottable()) throw Error(ErrorCode::Internal, "snapshot", "this detector cannot be snapshotted");
  save_params(out, detector.params());
  detector.save_state(out);
}

std::unique_ptr<CollisionDetector> load_detector(SnapshotReader& in) {
  const CollisionParams params = load_params(in);
  if (params.algorithm == CollisionAlgorithm::None) in.fail("algorithm", "a detector of algorithm none");
  if (params.inside != InsideMode::Nearest || params.swept) in.fail("inside", "an inside model is not snapshottable");
  std::unique_ptr<CollisionDetector> d = detail::make_narrow_detector(params);
  if (!d->snapshottable()) in.fail("algorithm", std::string(to_string(params.algorithm)) + " with these params is not snapshottable");
  d->load_state(in);
  return d;
}

namespace detail {

void check_rows(SnapshotReader& in, const IndexList& list, Index rows, const char* what) {
  Index last = -1;
  for (Index r : list) {
    if (r <= last || r >= rows) in.fail(what, "row " + std::to_string(r) + " not ascending in [0, " + std::to_string(rows) + ")");
    last = r;
  }
}

namespace {

void put_zero_set(SnapshotWriter& out, const ZeroSet& z) {
  out.mat(z.positions);
  out.mat(z.normals);
  out.mat(z.radii);
  out.vec(z.marked);
  out.vec(z.rows);
  out.f64(z.knn_eps);
}

// `cells`: the kernel's choice (ZeroSet::cells), not stored.
ZeroSet get_zero_set(SnapshotReader& in, Index rows, bool cells) {
  ZeroSet z;
  z.cells = cells;
  z.positions = in.mat<Points>("zero positions");
  z.normals = in.mat<Points>("zero normals");
  z.radii = in.mat<Values>("zero radii");
  z.marked = in.vec<std::uint8_t>("zero marks");
  z.rows = in.vec<Index>("zero rows");
  z.knn_eps = in.f64("zero knn_eps");
  const std::size_t n = z.rows.size();
  if (n == 0 || static_cast<std::size_t>(z.positions.rows()) != n || static_cast<std::size_t>(z.normals.rows()) != n ||
      static_cast<std::size_t>(z.radii.size()) != n || z.marked.size() != n) {
    in.fail("zero set", "arrays of different lengths");
  }
  check_rows(in, z.rows, rows, "zero rows");
  if (!(z.knn_eps >= 0.0) || !std::isfinite(z.knn_eps)) in.fail("zero knn_eps", "out of range");
  try {
    z.tree = std::make_shared<const KdTree>(z.positions, z.tree_params());
  } catch (const Error& e) {
    in.fail("zero positions", e.what());
  }
  return z;
}

}  // namespace

void ZeroSetKernel::save(SnapshotWriter& out) const { put_zero_set(out, zero_); }

void ZeroSetKernel::load(SnapshotReader& in, Index rows) { zero_ = get_zero_set(in, rows, zero_cells_); }

template <bool kHeld>
void RobustKernelT<kHeld>::save(SnapshotWriter& out) const {
  out.u64(static_cast<std::uint64_t>(original_rows()));
  out.vec(orig_.deformable.list());
  out.mat(orig_.positions);
  out.mat(orig_.normals);
  out.mat(orig_.radii);
  out.vec(orig_.alive);
  out.vec(orig_of_row_);
  out.vec(row_of_orig_);
  out.u64(orig_.tree ? orig_.tree->memory_bytes() : tree_bytes_);
}

// The zero rows are the model's: the tree over the original model is built at the first bind (the model is
// then where this detector saw it) or by on_rigid_moved (which is told where the moved rows were).
template <bool kHeld>
void RobustKernelT<kHeld>::load(SnapshotReader& in, Index rows) {
  const std::uint64_t n64 = in.u64("original rows count");
  if (n64 > static_cast<std::uint64_t>(std::numeric_limits<Index>::max())) in.fail("original rows count", "out of range");
  const Index n = static_cast<Index>(n64);
  const IndexList deformable = in.vec<Index>("original deformable rows");
  check_rows(in, deformable, n, "original deformable rows");
  Original orig;
  orig.deformable.assign(n, deformable);
  orig.positions = in.mat<Points>("original positions");
  orig.normals = in.mat<Points>("original normals");
  orig.radii = in.mat<Values>("original radii");
  orig.alive = in.vec<std::uint8_t>("original alive flags");
  IndexList orig_of_row = in.vec<Index>("original rows");
  IndexList row_of_orig = in.vec<Index>("model rows of the original");
  const std::size_t tree_bytes = in.capacity("original tree bytes", 0, 1);
  const std::size_t d = deformable.size();
  if (static_cast<std::size_t>(orig.positions.rows()) != d || static_cast<std::size_t>(orig.normals.rows()) != d ||
      static_cast<std::size_t>(orig.radii.size()) != d) {
    in.fail("original model", "arrays of different lengths");
  }
  if (!orig.positions.allFinite() || !orig.normals.allFinite() || !orig.radii.allFinite()) {
    in.fail("original positions", "not finite");
  }
  if (!orig.alive.empty() && orig.alive.size() != static_cast<std::size_t>(n)) in.fail("original alive flags", "not one per row");
  // Empty: the identity (no row inserted or removed since the reset), so the original model has one row per row.
  if ((orig_of_row.empty() ? static_cast<std::size_t>(n) : orig_of_row.size()) != static_cast<std::size_t>(rows)) {
    in.fail("original rows", "not one per model row");
  }
  for (Index o : orig_of_row)
    if (o < -1 || o >= n) in.fail("original rows", "row " + std::to_string(o) + " out of range");
  if (!row_of_orig.empty() && row_of_orig.size() != static_cast<std::size_t>(n)) in.fail("model rows of the original", "not one per row");
  for (Index r : row_of_orig)
    if (r < -1 || r >= rows) in.fail("model rows of the original", "row " + std::to_string(r) + " out of range");
  bool any_zero = false;
  for (Index o = 0; o < n; ++o) {
    const std::uint8_t a = orig.alive.empty() ? 1 : orig.alive[static_cast<std::size_t>(o)];
    if (a > 1) in.fail("original flags", "not 0 or 1");
    const Index r = row_of_orig.empty() ? o : row_of_orig[static_cast<std::size_t>(o)];
    if (!orig.deformable.test(o) && a && (r < 0 || r >= rows)) in.fail("model rows of the original", "a zero row outside the model");
    any_zero = any_zero || (!orig.deformable.test(o) && a);
  }
  if (!any_zero) in.fail("original model", "no zero surfel");
  orig_ = std::move(orig);
  orig_of_row_ = std::move(orig_of_row);
  row_of_orig_ = std::move(row_of_orig);
  inside_.reset();
  pending_inside_ = false;
  tree_bytes_ = tree_bytes;
  model_positions_ = model_normals_ = model_radii_ = nullptr;
}

template void RobustKernelT<false>::save(SnapshotWriter&) const;
template void RobustKernelT<false>::load(SnapshotReader&, Index);
template void RobustKernelT<true>::save(SnapshotWriter&) const;
template void RobustKernelT<true>::load(SnapshotReader&, Index);

}  // namespace detail
}  // namespace surfeledit
