#include "surfeledit/core/surfel_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

// Rows of an optional array must be 0 or #P; `expect` forces one of the two.
void check_optional_rows(Eigen::Index rows, Eigen::Index n, std::optional<bool> expect,
                         const char* field) {
  const bool present = rows != 0;
  if (present && rows != n) {
    std::ostringstream msg;
    msg << "has " << rows << " rows, expected " << n << " (one per position) or none";
    throw Error(ErrorCode::InvalidArgument, field, msg.str());
  }
  if (expect && *expect != present) {
    throw Error(ErrorCode::InvalidArgument, field,
                *expect ? "missing, but the model has this attribute"
                        : "given, but the model has no such attribute");
  }
}

// FNV-1a over raw bytes.
void hash_bytes(std::uint64_t& h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
}

// Unit clip directions; zero ones (unclipped) stay zero.
void normalise_clip_dirs(Points& dirs) {
  for (Eigen::Index i = 0; i < dirs.rows(); ++i) {
    const double len = dirs.row(i).norm();
    if (len > 0.0) dirs.row(i) /= len;
  }
}

}  // namespace

void validate_arrays(const SurfelArrays& a, std::optional<bool> expect_tangents,
                     std::optional<bool> expect_colors) {
  const Eigen::Index n = a.positions.rows();
  if (a.normals.rows() != n) {
    std::ostringstream msg;
    msg << "has " << a.normals.rows() << " rows, expected " << n << " (one per position)";
    throw Error(ErrorCode::InvalidArgument, "normals", msg.str());
  }
  if (a.radii.size() != 0 && a.radii.size() != n) {
    std::ostringstream msg;
    msg << "has " << a.radii.size() << " values, expected " << n << " (one per position) or none";
    throw Error(ErrorCode::InvalidArgument, "radii", msg.str());
  }
  check_optional_rows(a.tangent_u.rows(), n, expect_tangents, "tangent_u");
  check_optional_rows(a.tangent_v.rows(), n, expect_tangents, "tangent_v");
  if ((a.tangent_u.rows() == 0) != (a.tangent_v.rows() == 0)) {
    throw Error(ErrorCode::InvalidArgument, "tangent_v", "tangent_u and tangent_v come together");
  }
  check_optional_rows(a.colors.rows(), n, expect_colors, "colors");
  check_optional_rows(a.clip_points.rows(), n, std::nullopt, "clip_points");
  check_optional_rows(a.clip_dirs.rows(), n, std::nullopt, "clip_dirs");
  if ((a.clip_points.rows() == 0) != (a.clip_dirs.rows() == 0)) {
    throw Error(ErrorCode::InvalidArgument, "clip_dirs", "clip_points and clip_dirs come together");
  }

  require_finite(a.positions, "positions");
  require_finite(a.normals, "normals");
  require_finite(a.radii, "radii");
  require_finite(a.tangent_u, "tangent_u");
  require_finite(a.tangent_v, "tangent_v");
  require_finite(a.clip_points, "clip_points");
  require_finite(a.clip_dirs, "clip_dirs");
  for (Eigen::Index i = 0; i < n; ++i) {
    const double len2 = a.normals.row(i).squaredNorm();
    if (!(len2 > 1e-300)) {
      std::ostringstream msg;
      msg << "zero-length normal at row " << i;
      throw Error(ErrorCode::InvalidArgument, "normals", msg.str());
    }
  }
  for (Eigen::Index i = 0; i < a.radii.size(); ++i) {
    if (!(a.radii[i] > 0.0)) {
      std::ostringstream msg;
      msg << "radius " << a.radii[i] << " at row " << i << " is not positive";
      throw Error(ErrorCode::InvalidArgument, "radii", msg.str());
    }
  }
}

Values estimate_radii(const Points& positions, int k) {
  const Index n = static_cast<Index>(positions.rows());
  Values radii = Values::Ones(n);
  if (n < 2) return radii;
  const KdTree tree(positions);
  const int kk = std::min<int>(k + 1, n);  // +1: the point itself
  const KnnResult r = tree.knn(positions, kk);
  for (Index i = 0; i < n; ++i) {
    double sum = 0.0;
    int count = 0;
    for (int j = 0; j < kk; ++j) {
      const Index nb = r.indices(i, j);
      if (nb < 0 || nb == i) continue;
      sum += std::sqrt(r.dist2(i, j));
      ++count;
    }
    const double mean = count ? sum / count : 0.0;
    radii[i] = mean;
  }
  // Coincident points get the smallest positive radius of the model (or 1 if all coincide).
  double min_pos = 0.0;
  for (Index i = 0; i < n; ++i)
    if (radii[i] > 0.0 && (min_pos == 0.0 || radii[i] < min_pos)) min_pos = radii[i];
  for (Index i = 0; i < n; ++i)
    if (!(radii[i] > 0.0)) radii[i] = min_pos > 0.0 ? min_pos : 1.0;
  return radii;
}

SurfelModel SurfelModel::from_arrays(SurfelArrays arrays) {
  if (arrays.positions.rows() == 0) {
    throw Error(ErrorCode::InvalidArgument, "positions", "the model is empty (0 surfels)");
  }
  validate_arrays(arrays);
  arrays.normals.rowwise().normalize();
  if (arrays.radii.size() == 0) arrays.radii = estimate_radii(arrays.positions);
  normalise_clip_dirs(arrays.clip_dirs);

  SurfelModel m;
  const Index n = static_cast<Index>(arrays.positions.rows());
  m.a_ = std::move(arrays);
  m.next_id_ = static_cast<SurfelId>(n);  // ids 0..n-1: ids_ stays empty (the identity)
  return m;
}

IdList SurfelModel::ids() const {
  if (!ids_.empty()) return ids_;
  IdList out(static_cast<std::size_t>(size()));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<SurfelId>(i);
  return out;
}

void SurfelModel::spell_out_ids() {
  if (!ids_.empty()) return;
  ids_ = ids();
  IndexList set(ids_.begin(), ids_.end());
  alive_.assign(static_cast<Index>(next_id_), set);
}

IndexList SurfelModel::rows_of(const IdList& ids, const std::string& field) const {
  IndexList rows;
  rows.reserve(ids.size());
  std::vector<bool> seen(static_cast<std::size_t>(size()), false);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const Index r = row_of(ids[k]);
    if (r < 0) {
      std::ostringstream msg;
      msg << "unknown surfel id " << ids[k] << " (at position " << k << ")";
      throw Error(ErrorCode::NotFound, field, msg.str());
    }
    if (seen[r]) {
      std::ostringstream msg;
      msg << "surfel id " << ids[k] << " repeated (at position " << k << ")";
      throw Error(ErrorCode::InvalidArgument, field, msg.str());
    }
    seen[r] = true;
    rows.push_back(r);
  }
  return rows;
}

namespace {

template <typename M>
void append_rows(M& dst, const M& src) {
  if (src.rows() == 0) return;
  const Eigen::Index old = dst.rows();
  M out(old + src.rows(), dst.cols() ? dst.cols() : src.cols());
  if (old) out.topRows(old) = dst;
  out.bottomRows(src.rows()) = src;
  dst = std::move(out);
}

template <typename M>
M keep_rows(const M& src, const std::vector<bool>& keep, Eigen::Index kept) {
  if (src.rows() == 0) return src;
  M out(kept, src.cols());
  Eigen::Index j = 0;
  for (Eigen::Index i = 0; i < src.rows(); ++i)
    if (keep[i]) out.row(j++) = src.row(i);
  return out;
}

}  // namespace

IdList SurfelModel::insert(SurfelArrays added) {
  if (added.positions.rows() == 0) return {};
  validate_arrays(added, has_tangents(), has_colors());
  added.normals.rowwise().normalize();
  if (added.radii.size() == 0) {
    throw Error(ErrorCode::InvalidArgument, "radii", "inserted surfels need radii");
  }
  const Index n_add = static_cast<Index>(added.positions.rows());
  normalise_clip_dirs(added.clip_dirs);
  if (has_clips() || added.clip_dirs.rows() != 0) {
    // Either side without clip lines is unclipped (zero rows).
    if (!has_clips()) a_.clip_points = a_.clip_dirs = Points::Zero(size(), 3);
    if (added.clip_dirs.rows() == 0) added.clip_points = added.clip_dirs = Points::Zero(n_add, 3);
  }
  append_rows(a_.positions, added.positions);
  append_rows(a_.normals, added.normals);
  Values radii(a_.radii.size() + n_add);
  radii << a_.radii, added.radii;
  a_.radii = std::move(radii);
  append_rows(a_.tangent_u, added.tangent_u);
  append_rows(a_.tangent_v, added.tangent_v);
  append_rows(a_.colors, added.colors);
  append_rows(a_.clip_points, added.clip_points);
  append_rows(a_.clip_dirs, added.clip_dirs);

  IdList out(n_add);
  for (Index k = 0; k < n_add; ++k) {
    const SurfelId id = next_id_++;
    out[k] = id;
    if (ids_.empty()) continue;  // the identity continues: the new rows' ids are their rows
    alive_.push_back(true);
    ids_.push_back(id);
  }
  return out;
}

void SurfelModel::remove(const IdList& ids) {
  const IndexList rows = rows_of(ids, "ids");  // validates before anything changes
  if (static_cast<Index>(rows.size()) == size()) {
    throw Error(ErrorCode::Conflict, "ids", "removing every surfel would leave an empty model");
  }
  spell_out_ids();
  std::vector<bool> keep(ids_.size(), true);
  for (Index r : rows) keep[r] = false;
  const Eigen::Index kept = static_cast<Eigen::Index>(ids_.size() - rows.size());

  a_.positions = keep_rows(a_.positions, keep, kept);
  a_.normals = keep_rows(a_.normals, keep, kept);
  a_.tangent_u = keep_rows(a_.tangent_u, keep, kept);
  a_.tangent_v = keep_rows(a_.tangent_v, keep, kept);
  a_.colors = keep_rows(a_.colors, keep, kept);
  a_.clip_points = keep_rows(a_.clip_points, keep, kept);
  a_.clip_dirs = keep_rows(a_.clip_dirs, keep, kept);
  Values radii(kept);
  IdList kept_ids;
  kept_ids.reserve(kept);
  for (std::size_t i = 0, j = 0; i < ids_.size(); ++i) {
    if (!keep[i]) continue;
    radii[static_cast<Eigen::Index>(j)] = a_.radii[static_cast<Eigen::Index>(i)];
    kept_ids.push_back(ids_[i]);
    ++j;
  }
  a_.radii = std::move(radii);
  ids_ = std::move(kept_ids);
  alive_.assign(static_cast<Index>(next_id_), IndexList(ids_.begin(), ids_.end()));
}

std::uint64_t SurfelModel::hash() const {
  std::uint64_t h = 1469598103934665603ull;
  if (!ids_.empty()) {
    hash_bytes(h, ids_.data(), ids_.size() * sizeof(SurfelId));
  } else {  // the same bytes as the spelled-out list
    for (Index r = 0; r < size(); ++r) {
      const SurfelId id = static_cast<SurfelId>(r);
      hash_bytes(h, &id, sizeof(id));
    }
  }
  hash_bytes(h, a_.positions.data(), a_.positions.size() * sizeof(double));
  hash_bytes(h, a_.normals.data(), a_.normals.size() * sizeof(double));
  hash_bytes(h, a_.radii.data(), a_.radii.size() * sizeof(double));
  if (has_clips()) {  // only when present, so that hashes of unclipped models stay as they were
    hash_bytes(h, a_.clip_points.data(), a_.clip_points.size() * sizeof(double));
    hash_bytes(h, a_.clip_dirs.data(), a_.clip_dirs.size() * sizeof(double));
  }
  return h;
}

void SurfelModel::set_clips(const IdList& ids, const Points& points, const Points& dirs) {
  const auto n = static_cast<Eigen::Index>(ids.size());
  if (points.rows() != n || dirs.rows() != n) {
    std::ostringstream msg;
    msg << "clip_points has " << points.rows() << " rows and clip_dirs " << dirs.rows() << ", expected "
        << n << " (one per id)";
    throw Error(ErrorCode::InvalidArgument, points.rows() != n ? "clip_points" : "clip_dirs", msg.str());
  }
  require_finite(points, "clip_points");
  require_finite(dirs, "clip_dirs");
  const IndexList rows = rows_of(ids, "ids");
  if (!has_clips()) a_.clip_points = a_.clip_dirs = Points::Zero(size(), 3);
  Points unit = dirs;
  normalise_clip_dirs(unit);
  for (Eigen::Index k = 0; k < n; ++k) {
    a_.clip_points.row(rows[k]) = points.row(k);
    a_.clip_dirs.row(rows[k]) = unit.row(k);
  }
}

SurfelModel SurfelModel::from_parts(SurfelArrays arrays, IdList ids, SurfelId next_id) {
  const Eigen::Index n = static_cast<Eigen::Index>(ids.size());
  auto fits = [&](Eigen::Index rows, bool optional) { return rows == n || (optional && rows == 0); };
  const SurfelArrays& a = arrays;
  if (!fits(a.positions.rows(), false) || !fits(a.normals.rows(), false) || !fits(a.radii.size(), false) ||
      !fits(a.tangent_u.rows(), true) || a.tangent_v.rows() != a.tangent_u.rows() || !fits(a.colors.rows(), true) ||
      !fits(a.clip_points.rows(), true) || a.clip_dirs.rows() != a.clip_points.rows()) {
    throw Error(ErrorCode::InvalidArgument, "snapshot", "corrupt snapshot: model arrays of different lengths");
  }
  if (next_id > (SurfelId{1} << 40)) throw Error(ErrorCode::InvalidArgument, "snapshot", "corrupt snapshot: next id too large");
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] >= next_id || (i > 0 && ids[i] <= ids[i - 1])) {
      throw Error(ErrorCode::InvalidArgument, "snapshot", "corrupt snapshot: model ids not ascending below the next id");
    }
  }
  if (next_id > 16 * static_cast<SurfelId>(ids.size()) + (SurfelId{1} << 24)) {
    throw Error(ErrorCode::InvalidArgument, "snapshot", "corrupt snapshot: next id out of bounds");
  }
  SurfelModel m;
  m.a_ = std::move(arrays);
  m.next_id_ = next_id;
  // Ascending and below next_id: the identity exactly when there are next_id of them.
  if (next_id != static_cast<SurfelId>(ids.size())) {
    if (ids.empty()) throw Error(ErrorCode::InvalidArgument, "snapshot", "corrupt snapshot: an empty model with a next id");
    m.ids_ = std::move(ids);
    m.alive_.assign(static_cast<Index>(next_id), IndexList(m.ids_.begin(), m.ids_.end()));
  }
  return m;
}

std::size_t SurfelModel::memory_bytes() const {
  return sizeof(double) * (a_.positions.size() + a_.normals.size() + a_.radii.size() +
                           a_.tangent_u.size() + a_.tangent_v.size() + a_.clip_points.size() +
                           a_.clip_dirs.size()) +
         a_.colors.size() + ids_.size() * sizeof(SurfelId) +
         // by size, not capacity (like the arrays): a restored model reports what the live one did
         static_cast<std::size_t>((alive_.rows() + 63) / 64) * (sizeof(std::uint64_t) + sizeof(std::uint32_t));
}

Vec3 SurfelModel::min_corner() const {
  return empty() ? Vec3::Zero() : Vec3(a_.positions.colwise().minCoeff().transpose());
}
Vec3 SurfelModel::max_corner() const {
  return empty() ? Vec3::Zero() : Vec3(a_.positions.colwise().maxCoeff().transpose());
}
double SurfelModel::diagonal() const { return (max_corner() - min_corner()).norm(); }

}  // namespace surfeledit
