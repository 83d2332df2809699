// Deformation tool (docs/algorithms.md §1): blend fields from nearest-neighbour distances to F0 and F1, and
// one step F(p, s) = R(a, s alpha)(p - c) + c + s t applied to positions, normals and tangent axes.
#include "surfeledit/core/deformation.hpp"

#include <omp.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

#include "deformation_kernel.hpp"
#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string fmt(const Vec3& v) { return "(" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + ")"; }

int checked_threads(int threads, const char* field) {
  if (threads < 0) {
    throw Error(ErrorCode::InvalidArgument, field, "thread count must be >= 0, got " + std::to_string(threads));
  }
  return resolve_threads(threads);
}

bool valid_blend(Blend b) { return b == Blend::Smooth || b == Blend::Quadratic || b == Blend::Linear; }

}  // namespace

// smooth: beta = E(1 - l), E(x) = (x^2 - 1)^2, i.e. beta = l^2 (l - 2)^2; quadratic l^2; linear l.
double blend_value(Blend blend, double l) {
  switch (blend) {
    case Blend::Smooth: {
      const double q = l * (l - 2.0);
      return q * q;
    }
    case Blend::Quadratic: return l * l;
    case Blend::Linear: return l;
  }
  return l;
}

// d beta / d lambda: smooth 4 l (l - 1)(l - 2); quadratic 2 l; linear 1.
double blend_derivative(Blend blend, double l) {
  switch (blend) {
    case Blend::Smooth: return 4.0 * l * (l - 1.0) * (l - 2.0);
    case Blend::Quadratic: return 2.0 * l;
    case Blend::Linear: return 1.0;
  }
  return 1.0;
}

void validate(const DeformParams& params) {
  if (!params.translation.allFinite()) {
    throw Error(ErrorCode::InvalidArgument, "translation", "must be finite, got " + fmt(params.translation));
  }
  if (!std::isfinite(params.angle)) {
    throw Error(ErrorCode::InvalidArgument, "angle", "must be finite, got " + fmt(params.angle));
  }
  if (!params.axis.allFinite()) {
    throw Error(ErrorCode::InvalidArgument, "axis", "must be finite, got " + fmt(params.axis));
  }
  if (!(std::abs(params.angle) <= kMaxStepAngle)) {
    throw Error(ErrorCode::InvalidArgument, "angle",
                "must be within [-" + fmt(kMaxStepAngle) + ", " + fmt(kMaxStepAngle) + "] radians, got " +
                    fmt(params.angle));
  }
  if (params.angle != 0.0) {
    // The axis apply_step uses is axis / |axis|: it must come out of length 1 (a zero axis, or one whose
    // norm overflows or underflows, would make the rotation non-rigid).
    const double norm = params.axis.norm();
    const double unit = norm > 0.0 && std::isfinite(norm) ? (params.axis / norm).norm() : 0.0;
    if (!(std::abs(unit - 1.0) <= 1e-9)) {
      throw Error(ErrorCode::InvalidArgument, "axis",
                  "must normalise to a unit vector when angle != 0 (angle " + fmt(params.angle) + "), got " +
                      fmt(params.axis) + " (normalised length " + fmt(unit) + ")");
    }
  }
  if (params.center && !params.center->allFinite()) {
    throw Error(ErrorCode::InvalidArgument, "center", "must be finite, got " + fmt(*params.center));
  }
  if (!valid_blend(params.blend)) {
    throw Error(ErrorCode::InvalidArgument, "blend",
                "unknown blend value " + std::to_string(static_cast<int>(params.blend)));
  }
}

void validate(const DeformParams& params, const DeformationFields& fields) {
  validate(params);
  if (!std::isfinite(fields.box_extent)) return;
  const double reach = kStepReach * fields.box_extent;
  if (!(params.translation.norm() <= reach)) {
    throw Error(ErrorCode::InvalidArgument, "translation",
                "length " + fmt(params.translation.norm()) + " exceeds " + fmt(kStepReach) +
                    " times the model's extent (" + fmt(fields.box_extent) + "), got " + fmt(params.translation));
  }
  if (params.center && !((*params.center - fields.box_centre).norm() <= reach)) {
    throw Error(ErrorCode::InvalidArgument, "center",
                "lies " + fmt((*params.center - fields.box_centre).norm()) + " from the model, more than " +
                    fmt(kStepReach) + " times its extent (" + fmt(fields.box_extent) + "), got " +
                    fmt(*params.center));
  }
}

Values DeformationFields::lambda() const {
  Values out = Values::Zero(static_cast<Eigen::Index>(regions.size()));
  for (std::size_t k = 0; k < deformable.size(); ++k) out[deformable[k]] = blend_row(k)[0];
  return out;
}

Points DeformationFields::grad_lambda() const {
  Points out = Points::Zero(static_cast<Eigen::Index>(regions.size()), 3);
  for (std::size_t k = 0; k < deformable.size(); ++k)
    out.row(deformable[k]) = Eigen::Map<const Eigen::RowVector3d>(blend_row(k) + 1);
  return out;
}

double DeformationFields::lambda_of(Index row) const {
  const auto it = std::lower_bound(deformable.begin(), deformable.end(), row);
  if (it == deformable.end() || *it != row) return 0.0;
  return blend_row(static_cast<std::size_t>(it - deformable.begin()))[0];
}

std::size_t DeformationFields::memory_bytes() const {
  return regions.capacity() * sizeof(Region) + deformable.capacity() * sizeof(Index) +
         static_cast<std::size_t>(blend.size()) * sizeof(double);
}

DeformationFields compute_fields(const Points& positions, const std::vector<Region>& regions, int threads) {
  const int nthreads = checked_threads(threads, "threads");
  const Eigen::Index n = positions.rows();
  if (static_cast<Eigen::Index>(regions.size()) != n) {
    throw Error(ErrorCode::InvalidArgument, "regions",
                "has " + std::to_string(regions.size()) + " entries but positions have " + std::to_string(n) +
                    " rows");
  }
  require_finite(positions, "positions");
  // Squared distances of coordinates beyond kMaxCoordinate overflow: the nearest-neighbour search would
  // find nothing (and the fields index row -1).
  if (n > 0 && positions.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    throw Error(ErrorCode::InvalidArgument, "positions",
                "coordinates beyond " + fmt(kMaxCoordinate) + " model units (largest " +
                    fmt(positions.cwiseAbs().maxCoeff()) + "): nearest-neighbour distances would overflow");
  }
  IndexList f0, f1;
  DeformationFields fields;
  fields.regions = regions;
  if (n > 0) {  // the reference of the step bounds (validate(params, fields))
    const Eigen::RowVector3d lo = positions.colwise().minCoeff(), hi = positions.colwise().maxCoeff();
    fields.box_centre = (0.5 * (lo + hi)).transpose();
    fields.box_extent = (hi - lo).norm();
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    switch (regions[static_cast<std::size_t>(i)]) {
      case Region::Zero: f0.push_back(static_cast<Index>(i)); break;
      case Region::One: f1.push_back(static_cast<Index>(i)); fields.deformable.push_back(static_cast<Index>(i)); break;
      case Region::Blend: fields.deformable.push_back(static_cast<Index>(i)); break;
      default:
        throw Error(ErrorCode::InvalidArgument, "regions",
                    "row " + std::to_string(i) + " has unknown region value " +
                        std::to_string(static_cast<int>(regions[static_cast<std::size_t>(i)])));
    }
  }
  if (f0.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the zero region F0 is empty");
  if (f1.empty()) throw Error(ErrorCode::InvalidArgument, "regions", "the one region F1 is empty");

  KdTreeParams tp;
  tp.threads = nthreads;
  const KdTree tree0(positions, f0, tp);
  const KdTree tree1(positions, f1, tp);

  const Eigen::Index nd = static_cast<Eigen::Index>(fields.deformable.size());
  // Every deformable row in F1 (a rigid tool): all blend rows are kF1Blend, none is stored.
  const bool all_one = std::all_of(fields.deformable.begin(), fields.deformable.end(),
                                   [&](Index i) { return regions[static_cast<std::size_t>(i)] == Region::One; });
  fields.blend.setZero(all_one ? 0 : nd, 4);
  Index conflict = std::numeric_limits<Index>::max();
  // Every row is checked against the region it is not in (F0 rows against F1 too), so a surfel
  // lying in both (d0 + d1 == 0) is reported whatever its label.
  const Eigen::Index n0 = static_cast<Eigen::Index>(f0.size());
#pragma omp parallel for schedule(static) num_threads(nthreads) reduction(min : conflict)
  for (Eigen::Index q = 0; q < n0; ++q) {
    const Index i = f0[static_cast<std::size_t>(q)];
    const Vec3 p = positions.row(i).transpose();
    if ((p - positions.row(tree1.nearest(p)).transpose()).norm() == 0.0) conflict = std::min(conflict, i);
  }
#pragma omp parallel for schedule(static) num_threads(nthreads) reduction(min : conflict)
  for (Eigen::Index k = 0; k < nd; ++k) {
    const Index i = fields.deformable[static_cast<std::size_t>(k)];
    const bool one = regions[static_cast<std::size_t>(i)] == Region::One;
    const Vec3 p = positions.row(i).transpose();
    // Offsets to the nearest F0 / F1 surfel (model units) and their real (not squared) lengths.
    const Vec3 e0 = p - positions.row(tree0.nearest(p)).transpose();
    Vec3 e1 = Vec3::Zero();
    if (!one) e1 = p - positions.row(tree1.nearest(p)).transpose();
    const double d0 = e0.norm(), d1 = e1.norm();
    if (d0 + d1 == 0.0) {
      conflict = std::min(conflict, i);
      continue;
    }
    if (one) {
      if (!all_one) fields.blend(k, 0) = 1.0;  // lambda 1, gradient 0
      continue;
    }
    const double sum = d0 + d1;
    fields.blend(k, 0) = d0 / sum;
    // grad lambda = (d1 grad d0 - d0 grad d1) / (d0 + d1)^2, grad d = offset / d (units 1 / model unit);
    // left at zero where a distance vanishes (direction undefined; lambda is at an end there).
    if (d0 > 0.0 && d1 > 0.0) {
      fields.blend.block<1, 3>(k, 1) = ((d1 / d0) * e0 - (d0 / d1) * e1).transpose() / (sum * sum);
    }
  }
  if (conflict != std::numeric_limits<Index>::max()) {
    throw Error(ErrorCode::Conflict, "regions",
                "row " + std::to_string(conflict) +
                    " lies in both F0 and F1 (d0 + d1 == 0): the regions overlap");
  }
  return fields;
}

namespace {

// beta and beta' for one blend, inlined into the step's loops.
template <Blend B>
inline double beta(double l) {
  if constexpr (B == Blend::Smooth) {
    const double q = l * (l - 2.0);
    return q * q;
  } else if constexpr (B == Blend::Quadratic) {
    return l * l;
  } else {
    return l;
  }
}
template <Blend B>
inline double beta_prime(double l) {
  if constexpr (B == Blend::Smooth) {
    return 4.0 * l * (l - 1.0) * (l - 2.0);
  } else if constexpr (B == Blend::Quadratic) {
    return 2.0 * l;
  } else {
    return 1.0;
  }
}

// The validation / `moved` pass for one blend: checks every listed row (ascending, in range, deformable,
// 0 <= lambda <= 1), collects the moved rows (s > 0) and their positions in `deformable`, and F1's centroid.
template <Blend B>
void scan_rows(const DeformationFields& fields, const IndexList* ks_in, Eigen::Index n, bool need_centroid,
               DeformResult& result, IndexList& ks, Vec3& f1_ref, Vec3& f1_sum, std::size_t& f1_count,
               const double* Pc) {
  const std::size_t count = ks_in ? ks_in->size() : fields.deformable.size();
  Index prev = -1;
  for (std::size_t q = 0; q < count; ++q) {
    const std::size_t k = ks_in ? static_cast<std::size_t>((*ks_in)[q]) : q;
    const Index i = fields.deformable[k];
    if (i <= prev || i >= n) {
      throw Error(ErrorCode::InvalidArgument, "fields.deformable",
                  "row " + std::to_string(i) + " is out of range or not ascending");
    }
    prev = i;
    const Region region = fields.regions[static_cast<std::size_t>(i)];
    const double l = fields.blend_row(k)[0];
    if (region == Region::Zero || !(l >= 0.0 && l <= 1.0) || (fields.blend.rows() == 0 && region != Region::One)) {
      throw Error(ErrorCode::InvalidArgument, "fields",
                  "row " + std::to_string(i) + " is listed as deformable with region " +
                      std::to_string(static_cast<int>(region)) + " and lambda " + fmt(l));
    }
    if (need_centroid && region == Region::One) {
      const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(i);
      const Vec3 p(Pc[o], Pc[o + 1], Pc[o + 2]);
      if (f1_count == 0) f1_ref = p;
      f1_sum += p - f1_ref;
      ++f1_count;
    }
    if (beta<B>(l) > 0.0) {
      result.moved.push_back(i);
      ks.push_back(static_cast<Index>(k));
    }
  }
}

// The usual step (no `only`): one branch-free pass that checks every deformable row as scan_rows does and
// sums F1's centroid the same way (a row that is not F1 adds +0, which changes no sum that starts at +0).
// True when every row is valid and moves (s > 0): `moved` is then fields.deformable itself. False: nothing
// is known, scan_rows runs (and throws the error, naming the row).
template <Blend B, bool need_centroid>
bool scan_all_moving(const DeformationFields& fields, Eigen::Index n, const double* Pc, Vec3& f1_ref, Vec3& f1_sum,
                     std::size_t& f1_count) {
  const std::size_t count = fields.deformable.size();
  const Index* rows = fields.deformable.data();
  const Region* regions = fields.regions.data();
  const double* F = fields.blend_row(0);
  const std::ptrdiff_t fs = fields.blend_stride();
  const bool stored = fs != 0;  // without stored rows every row must be F1
  if constexpr (need_centroid) {  // the reference: the first F1 row
    std::size_t k = 0;
    while (k < count && !(rows[k] >= 0 && rows[k] < n && regions[rows[k]] == Region::One)) ++k;
    if (k == count) return false;  // no F1 row: scan_rows finds the count 0
    const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(rows[k]);
    f1_ref = Vec3(Pc[o], Pc[o + 1], Pc[o + 2]);
  }
  const double rx = f1_ref.x(), ry = f1_ref.y(), rz = f1_ref.z();
  double sx = 0.0, sy = 0.0, sz = 0.0;
  std::size_t ones = 0;
  bool ok = true;
  Index prev = -1;
  for (std::size_t k = 0; k < count; ++k) {
    const Index i = rows[k];
    const bool in = (i > prev) & (i < n);
    prev = i;
    const Index j = in ? i : 0;  // a row that may be read
    const Region region = regions[j];
    const double l = F[fs * static_cast<std::ptrdiff_t>(k)];
    ok &= in & (region != Region::Zero) & (stored | (region == Region::One)) & (l >= 0.0) & (l <= 1.0) &
          (beta<B>(l) > 0.0);
    if constexpr (need_centroid) {
      const bool one = region == Region::One;
      const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(j);
      sx += one ? Pc[o] - rx : 0.0;
      sy += one ? Pc[o + 1] - ry : 0.0;
      sz += one ? Pc[o + 2] - rz : 0.0;
      ones += one;
    }
  }
  if (!ok) return false;
  f1_sum = Vec3(sx, sy, sz);
  f1_count = ones;
  return true;
}

}  // namespace

bool step_kernel_available(StepKernel kernel) {
  switch (kernel) {
    case StepKernel::Auto:
    case StepKernel::Baseline: return true;
    case StepKernel::Avx2:
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
      return detail::avx2_block(Blend::Smooth, true, false) != nullptr && __builtin_cpu_supports("avx2");
#else
      return false;
#endif
  }
  return false;
}

DeformResult apply_step(const DeformationFields& fields, const DeformParams& params, Points& positions,
                        Points& normals, Points* tangent_u, Points* tangent_v, int threads, const IndexList* only,
                        StepKernel kernel) {
  // ---- validation: nothing below this block may throw after an array was written ----
  validate(params, fields);
  if (kernel != StepKernel::Auto && !step_kernel_available(kernel)) {
    throw Error(ErrorCode::InvalidArgument, "kernel",
                "kernel " + std::to_string(static_cast<int>(kernel)) + " is not available on this CPU or build");
  }
  const int nthreads = checked_threads(threads, "threads");
  const Eigen::Index n = positions.rows();
  auto require_rows = [n](Eigen::Index rows, const char* field) {
    if (rows != n) {
      throw Error(ErrorCode::InvalidArgument, field,
                  "has " + std::to_string(rows) + " rows but positions have " + std::to_string(n));
    }
  };
  require_rows(static_cast<Eigen::Index>(fields.regions.size()), "fields.regions");
  if (fields.blend.rows() != 0 && fields.blend.rows() != static_cast<Eigen::Index>(fields.deformable.size())) {
    throw Error(ErrorCode::InvalidArgument, "fields.blend",
                "has " + std::to_string(fields.blend.rows()) + " rows but fields.deformable lists " +
                    std::to_string(fields.deformable.size()) + " (0 rows: every deformable row in F1)");
  }
  require_rows(normals.rows(), "normals");
  const bool has_u = tangent_u && tangent_u->rows() > 0;
  const bool has_v = tangent_v && tangent_v->rows() > 0;
  if (has_u) require_rows(tangent_u->rows(), "tangent_u");
  if (has_v) require_rows(tangent_v->rows(), "tangent_v");
  if (has_u != has_v) {
    throw Error(ErrorCode::InvalidArgument, has_u ? "tangent_v" : "tangent_u",
                "tangent axes come in pairs: both or neither");
  }

  // `only`: its rows' positions in fields.deformable (both lists ascending: one merge walk).
  IndexList only_ks;
  if (only) {
    only_ks.reserve(only->size());
    std::size_t k = 0;
    Index prev = -1;
    for (const Index r : *only) {
      while (k < fields.deformable.size() && fields.deformable[k] < r) ++k;
      if (r <= prev || k == fields.deformable.size() || fields.deformable[k] != r) {
        throw Error(ErrorCode::InvalidArgument, "only",
                    "row " + std::to_string(r) + " is not deformable or the rows are not ascending");
      }
      prev = r;
      only_ks.push_back(static_cast<Index>(k));
    }
  }

  // One pass over the listed deformable rows: check the fields, collect the moved rows (s > 0) and, when
  // no centre is given, F1's centroid (shifted mean relative to the first F1 row, for precision far
  // from the origin). The model arrays themselves are not scanned for non-finite values here: the
  // step is memory-bound and a second full read of positions/normals would double its cost; they were
  // validated where they entered (compute_fields, the model), and a non-finite F1 position still shows up
  // as a non-finite centroid below.
  DeformResult result;
  IndexList ks;  // positions in fields.deformable of the moved rows (empty when every deformable row moves)
  Vec3 f1_ref = Vec3::Zero(), f1_sum = Vec3::Zero();
  std::size_t f1_count = 0;
  const bool need_centroid = !params.center;
  const IndexList* ks_in = only ? &only_ks : nullptr;
  auto scan = [&](auto blend) {
    constexpr Blend B = decltype(blend)::value;
    const bool all = !only && (need_centroid ? scan_all_moving<B, true>(fields, n, positions.data(), f1_ref, f1_sum, f1_count)
                                             : scan_all_moving<B, false>(fields, n, positions.data(), f1_ref, f1_sum, f1_count));
    if (all) {
      result.moved = fields.deformable;
      return true;
    }
    f1_ref = f1_sum = Vec3::Zero();
    f1_count = 0;
    const std::size_t listed = only ? only_ks.size() : fields.deformable.size();
    result.moved.reserve(listed);
    ks.reserve(listed);
    scan_rows<B>(fields, ks_in, n, need_centroid, result, ks, f1_ref, f1_sum, f1_count, positions.data());
    return false;
  };
  bool all_moving = false;
  switch (params.blend) {
    case Blend::Smooth: all_moving = scan(std::integral_constant<Blend, Blend::Smooth>()); break;
    case Blend::Quadratic: all_moving = scan(std::integral_constant<Blend, Blend::Quadratic>()); break;
    case Blend::Linear: all_moving = scan(std::integral_constant<Blend, Blend::Linear>()); break;
  }
  if (params.center) {
    result.center = *params.center;
  } else {
    if (f1_count == 0) {
      throw Error(ErrorCode::InvalidArgument, "center", "no centre given and the one region F1 is empty");
    }
    result.center = f1_ref + f1_sum / static_cast<double>(f1_count);
    if (!result.center.allFinite()) {
      throw Error(ErrorCode::InvalidArgument, "positions", "F1 holds a non-finite position");
    }
  }

  // ---- step constants ----
  const bool rotate = params.angle != 0.0;
  const Vec3 a = rotate ? Vec3(params.axis.normalized()) : Vec3::UnitZ();
  const Vec3 c = result.center, t = params.translation;
  const Vec3 axt = a.cross(t);
  detail::StepConstants sc{c.x(), c.y(), c.z(), t.x(), t.y(), t.z(), a.x(), a.y(), a.z(), params.angle,
                           axt.x(), axt.y(), axt.z(), a.dot(t), {}, std::abs(params.angle) <= detail::kNoReduction};
  {  // Rodrigues: R = cs I + sn [a]x + (1 - cs) a a^T
    const double cs = std::cos(params.angle), sn = std::sin(params.angle), k = 1.0 - cs;
    const double kxy = k * a.x() * a.y(), kxz = k * a.x() * a.z(), kyz = k * a.y() * a.z();
    const double r1[9] = {cs + k * a.x() * a.x(), kxy - sn * a.z(), kxz + sn * a.y(),
                          kxy + sn * a.z(), cs + k * a.y() * a.y(), kyz - sn * a.x(),
                          kxz - sn * a.y(), kyz + sn * a.x(), cs + k * a.z() * a.z()};
    std::copy(r1, r1 + 9, sc.r1);
  }
  const bool avx2 = kernel == StepKernel::Avx2 || (kernel == StepKernel::Auto && step_kernel_available(StepKernel::Avx2));
  const detail::BlockFn block = avx2 ? detail::avx2_block(params.blend, rotate, has_u)
                                     : detail::pick_block<detail::D2>(params.blend, rotate, has_u);
  // Every listed row moves (the usual case): blocks of consecutive positions, no index list.
  const bool consecutive = all_moving || (!only && ks.size() == fields.deformable.size());
  const Eigen::Index n_moved = static_cast<Eigen::Index>(all_moving ? fields.deformable.size() : ks.size());
  const Eigen::Index n_blocks = (n_moved + detail::kStepBlock - 1) / detail::kStepBlock;
  const Index* rows = fields.deformable.data();
  const double* F = fields.blend_row(0);
  const std::ptrdiff_t fs = fields.blend_stride();
  double* P = positions.data();
  double* N = normals.data();
  double* U = has_u ? tangent_u->data() : nullptr;
  double* V = has_v ? tangent_v->data() : nullptr;
  auto run = [&](Eigen::Index b) {
    const Eigen::Index k0 = b * detail::kStepBlock;
    const int count = static_cast<int>(std::min<Eigen::Index>(detail::kStepBlock, n_moved - k0));
    block(sc, rows, F, fs, consecutive ? nullptr : ks.data() + k0, k0, count, P, N, U, V);
  };
  // Several threads only for about a millisecond of one-thread work or more (~20 ns a row with a
  // rotation, RESULTS §24): below that, on a busy machine, waking a descheduled worker costs a scheduler
  // tick, more than the whole loop (RESULTS §35; the detector's rule is the same, row_detector.hpp).
  constexpr Eigen::Index kParallelMinMoved = 50000;
  if (nthreads == 1 || n_moved < kParallelMinMoved) {
    for (Eigen::Index b = 0; b < n_blocks; ++b) run(b);
  } else {
#pragma omp parallel for schedule(static) num_threads(nthreads)
    for (Eigen::Index b = 0; b < n_blocks; ++b) run(b);
  }
  return result;
}

std::optional<double> displacement_bound(const DeformParams& params) {
  if (params.angle != 0.0) return std::nullopt;
  // The margin covers the norm's rounding and blend values a few ulps above 1.
  return 2.0 * params.translation.norm() * (1.0 + 1e-12);
}

}  // namespace surfeledit
