// The usual step's check of its rows (apply_step without `only`, docs/algorithms.md §1): every deformable row
// is ascending, in range, not F0, has 0 <= lambda <= 1 (F1 without stored blend rows) and moves (beta > 0);
// on the way, F1's centroid is summed relative to the first F1 row, in row order. Included by
// deformation_step.cpp (the row-by-row scan, the baseline) and deformation_avx2.cpp (eight rows at a time):
// both sum the same terms in the same order, so the centroid has the same bits (test
// DeformationKernels.ScansRefuseEveryBadRowAndAgree).
#pragma once

#include <cstddef>

#include "surfeledit/core/deformation.hpp"

namespace surfeledit::detail {

// One scan: its input (the fields' arrays and the positions) and the centroid sums it makes.
struct RowScan {
  const Index* rows;      // fields.deformable (#D, ascending when valid)
  std::size_t count;      // #D
  Eigen::Index n;         // rows of the model
  const Region* regions;  // fields.regions (#P)
  const double* F;        // fields.blend_row(0)
  std::ptrdiff_t fs;      // fields.blend_stride(): 4, or 0 (every row is kF1Blend)
  const double* P;        // positions, #P by 3 row-major
  double rx = 0.0, ry = 0.0, rz = 0.0;  // the reference: the first F1 row's position (when summing)
  double sx = 0.0, sy = 0.0, sz = 0.0;  // sum over F1 rows of (p - reference), in row order
  std::size_t ones = 0;                 // F1 rows seen
  Index prev = -1;                      // the last row checked (the next must be larger)
};

// Checks rows [0, count) and, with the centroid, sums F1; true when every row is valid and moves. False
// says nothing of where: the caller's row-by-row pass finds the row and names it.
using ScanFn = bool (*)(RowScan&);

// The AVX2 scan (deformation_avx2.cpp); null when this build has none.
ScanFn avx2_scan(Blend blend, bool centroid);

namespace {

// beta(lambda) for one blend.
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

// Whether a listed deformable row's region and lambda are valid: not F0, 0 <= lambda <= 1, and F1 when the fields
// store no blend rows (`stored_blend` false). Bitwise, so that a scan using it stays branch-free; the row-by-row
// pass that names a bad row (deformation_step.cpp) asks the same.
inline bool valid_row(Region region, double l, bool stored_blend) {
  return (region != Region::Zero) & (stored_blend | (region == Region::One)) & (l >= 0.0) & (l <= 1.0);
}

// Row k of a scan, branch-free: whether it is valid and moves; adds it to the centroid when it is F1.
template <Blend B, bool kCentroid>
inline bool scan_row(RowScan& s, std::size_t k) {
  const Index i = s.rows[k];
  const bool in = (i > s.prev) & (i < s.n);
  s.prev = i;
  const Index j = in ? i : 0;  // a row that may be read
  const Region region = s.regions[j];
  const double l = s.F[s.fs * static_cast<std::ptrdiff_t>(k)];
  const bool ok = in & valid_row(region, l, s.fs != 0) & (beta<B>(l) > 0.0);
  if constexpr (kCentroid) {  // a row that is not F1 adds +0, which changes no sum that starts at +0
    const bool one = region == Region::One;
    const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(j);
    s.sx += one ? s.P[o] - s.rx : 0.0;
    s.sy += one ? s.P[o + 1] - s.ry : 0.0;
    s.sz += one ? s.P[o + 2] - s.rz : 0.0;
    s.ones += one;
  }
  return ok;
}

// Rows [k, count) one at a time. The loop works on a copy of the scan: the sums then stay in registers
// (a store to the caller's scan could alias the positions it reads).
template <Blend B, bool kCentroid>
inline bool scan_rows_from(RowScan& s, std::size_t k) {
  RowScan t = s;
  bool ok = true;
  for (; k < t.count; ++k) ok &= scan_row<B, kCentroid>(t, k);
  s = t;
  return ok;
}

}  // namespace
}  // namespace surfeledit::detail
