// Deformation step (docs/algorithms.md §1): F(p, s) = R(a, s alpha)(p - c) + c + s t applied to positions,
// normals and tangent axes of the rows the fields (deformation.cpp) let move.
#include "surfeledit/core/deformation.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "deformation_checks.hpp"
#include "deformation_kernel.hpp"
#include "deformation_scan.hpp"
#include "share_chunks.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

using deformation_checks::checked_threads;
using deformation_checks::fmt;

namespace {

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
    if (!detail::valid_row(region, l, fields.blend.rows() != 0)) {
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
    if (detail::beta<B>(l) > 0.0) {
      result.moved.push_back(i);
      ks.push_back(static_cast<Index>(k));
    }
  }
}

// The usual step's scan (deformation_scan.hpp) one row at a time.
template <Blend B, bool kCentroid>
bool scan_baseline(detail::RowScan& s) {
  return detail::scan_rows_from<B, kCentroid>(s, 0);
}

template <bool kCentroid>
detail::ScanFn pick_scan(Blend blend, bool avx2) {
  if (avx2) {
    if (const detail::ScanFn f = detail::avx2_scan(blend, kCentroid)) return f;
  }
  switch (blend) {
    case Blend::Smooth: return scan_baseline<Blend::Smooth, kCentroid>;
    case Blend::Quadratic: return scan_baseline<Blend::Quadratic, kCentroid>;
    case Blend::Linear: return scan_baseline<Blend::Linear, kCentroid>;
  }
  return nullptr;
}

// The usual step (no `only`): one branch-free scan checks every deformable row as scan_rows does and sums F1's
// centroid the same way. True when every row is valid and moves (s > 0): `moved` is then fields.deformable
// itself. False: nothing is known, scan_rows runs (and throws the error, naming the row).
bool scan_all_moving(const DeformationFields& fields, Blend blend, bool avx2, bool need_centroid, Eigen::Index n,
                     const double* Pc, Vec3& f1_ref, Vec3& f1_sum, std::size_t& f1_count) {
  detail::RowScan s{fields.deformable.data(), fields.deformable.size(), n, fields.regions.data(),
                    fields.blend_row(0),      fields.blend_stride(),    Pc};
  if (need_centroid) {  // the reference: the first F1 row
    std::size_t k = 0;
    const Index* rows = s.rows;
    while (k < s.count && !(rows[k] >= 0 && rows[k] < n && s.regions[rows[k]] == Region::One)) ++k;
    if (k == s.count) return false;  // no F1 row: scan_rows finds the count 0
    const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(rows[k]);
    s.rx = Pc[o], s.ry = Pc[o + 1], s.rz = Pc[o + 2];
    f1_ref = Vec3(s.rx, s.ry, s.rz);
  }
  const detail::ScanFn scan = need_centroid ? pick_scan<true>(blend, avx2) : pick_scan<false>(blend, avx2);
  if (!scan(s)) return false;
  f1_sum = Vec3(s.sx, s.sy, s.sz);
  f1_count = s.ones;
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
  const bool avx2 = kernel == StepKernel::Avx2 || (kernel == StepKernel::Auto && step_kernel_available(StepKernel::Avx2));
  auto scan = [&](auto blend) {
    constexpr Blend B = decltype(blend)::value;
    const bool all = !only && scan_all_moving(fields, B, avx2, need_centroid, n, positions.data(), f1_ref, f1_sum, f1_count);
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
    return block(sc, rows, F, fs, consecutive ? nullptr : ks.data() + k0, k0, count, P, N, U, V);
  };
  // Several threads only for about a millisecond of one-thread work or more (~5 ns a row with a rotation
  // since RESULTS §70): below that, on a busy machine, waking a descheduled worker costs a scheduler tick,
  // more than the whole loop (RESULTS §35; the detector's rule is the same, parallel_sweep.hpp). And rows
  // one thread moves and another then reads cross between the cores' caches: a 60k step split over two
  // threads made the detector's one-thread sweep after it 3.3x slower (RESULTS §89).
  bool finite = true;
  if (nthreads == 1 || n_moved < static_cast<Eigen::Index>(kStepParallelMinMoved)) {
    for (Eigen::Index b = 0; b < n_blocks; ++b) finite &= run(b);
  } else {
    // Chunks of 64 blocks (4096 rows, tens of microseconds), shared without waiting for a descheduled helper.
    constexpr Eigen::Index kBlocksPerChunk = 64;
    const Eigen::Index chunks = (n_blocks + kBlocksPerChunk - 1) / kBlocksPerChunk;
    std::vector<std::uint8_t> chunk_finite(static_cast<std::size_t>(chunks), 1);
    detail::share_chunks(nthreads, chunks, [&](Index c) {
      bool ok = true;
      for (Eigen::Index b = c * kBlocksPerChunk; b < std::min(n_blocks, (c + 1) * kBlocksPerChunk); ++b) ok &= run(b);
      chunk_finite[static_cast<std::size_t>(c)] = ok;
    });
    for (const std::uint8_t ok : chunk_finite) finite &= ok != 0;
  }
  result.finite = finite;
  return result;
}

std::optional<double> displacement_bound(const DeformParams& params) {
  if (params.angle != 0.0) return std::nullopt;
  // The margin covers the norm's rounding and blend values a few ulps above 1.
  return 2.0 * params.translation.norm() * (1.0 + 1e-12);
}

}  // namespace surfeledit
