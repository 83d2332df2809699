// The deformation step four rows at a time (AVX2; deformation_kernel.hpp) and its scan of the rows eight at a
// time (deformation_scan.hpp). This file alone is built with -mavx2 (and without fused multiply-adds, so the
// bits are the baseline's); apply_step calls it only on a CPU that has AVX2 (step_kernel_available).
#include <algorithm>
#include <cstdint>
#include <limits>

#include "deformation_kernel.hpp"
#include "deformation_scan.hpp"

#if defined(__AVX2__) && !defined(__FMA__)
#include <immintrin.h>
#endif

namespace surfeledit::detail {

#if defined(__AVX2__) && !defined(__FMA__)
BlockFn avx2_block(Blend blend, bool rotate, bool tangents) { return pick_block<D4>(blend, rotate, tangents); }

namespace {

// beta(lambda) of four rows: the same operations as detail::beta.
template <Blend B>
inline __m256d beta4(__m256d l) {
  if constexpr (B == Blend::Smooth) {
    const __m256d q = _mm256_mul_pd(l, _mm256_sub_pd(l, _mm256_set1_pd(2.0)));
    return _mm256_mul_pd(q, q);
  } else if constexpr (B == Blend::Quadratic) {
    return _mm256_mul_pd(l, l);
  } else {
    return l;
  }
}

// Bit j set when lambda of lane j passes: 0 <= l <= 1 and beta(l) > 0 (false for NaN, as the scalar tests).
template <Blend B>
inline int lambda_bits(__m256d l) {
  const __m256d in = _mm256_and_pd(_mm256_cmp_pd(l, _mm256_setzero_pd(), _CMP_GE_OQ),
                                   _mm256_cmp_pd(l, _mm256_set1_pd(1.0), _CMP_LE_OQ));
  return _mm256_movemask_pd(_mm256_and_pd(in, _mm256_cmp_pd(beta4<B>(l), _mm256_setzero_pd(), _CMP_GT_OQ)));
}

inline int bits8(__m256i m) { return _mm256_movemask_ps(_mm256_castsi256_ps(m)); }

// lambda of four consecutive blend rows from f on (every fourth double). The masked gather with a zero source
// is the plain one; GCC 12's plain form starts from an undefined register and warns.
inline __m256d lambdas(const double* f) {
  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  return _mm256_mask_i32gather_pd(_mm256_setzero_pd(), f, _mm_setr_epi32(0, 4, 8, 12), all, 8);
}

// Eight rows at a time: the rows (one load), their predecessors (a lane rotation), the regions (a gather of
// four bytes at each row, kept to rows <= n - 4 so that it stays inside the array; a block with another row
// goes row by row) and lambda (a gather of every fourth double). F1 rows are added to the centroid in row
// order, as the row-by-row scan adds them; it also adds +0 for the others, which changes no sum.
template <Blend B, bool kCentroid>
bool scan_avx2(RowScan& s) {
  const long long last_gathered = std::min<long long>(static_cast<long long>(s.n) - 4, std::numeric_limits<Index>::max());
  if (last_gathered < 0) return scan_rows_from<B, kCentroid>(s, 0);
  const __m256i lim = _mm256_set1_epi32(static_cast<Index>(last_gathered));
  const __m256i minus_one = _mm256_set1_epi32(-1), low_byte = _mm256_set1_epi32(0xFF);
  const __m256i zero = _mm256_set1_epi32(static_cast<int>(Region::Zero)), one = _mm256_set1_epi32(static_cast<int>(Region::One));
  const __m256i previous_lane = _mm256_setr_epi32(7, 0, 1, 2, 3, 4, 5, 6);
  const bool stored = s.fs != 0;
  double sx = s.sx, sy = s.sy, sz = s.sz;  // in registers (a store to `s` could alias the positions)
  std::size_t k = 0;
  for (; k + 8 <= s.count; k += 8) {
    const __m256i r = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(s.rows + k));
    const __m256i gatherable = _mm256_andnot_si256(_mm256_cmpgt_epi32(r, lim), _mm256_cmpgt_epi32(r, minus_one));
    if (bits8(gatherable) != 0xFF) {
      s.sx = sx, s.sy = sy, s.sz = sz;
      bool ok = true;
      for (std::size_t e = k + 8; k < e; ++k) ok &= scan_row<B, kCentroid>(s, k);
      if (!ok) return false;
      sx = s.sx, sy = s.sy, sz = s.sz;
      k -= 8;  // the loop's step
      continue;
    }
    const __m256i before = _mm256_blend_epi32(_mm256_permutevar8x32_epi32(r, previous_lane), _mm256_set1_epi32(s.prev), 0x01);
    const __m256i region = _mm256_and_si256(_mm256_i32gather_epi32(reinterpret_cast<const int*>(s.regions), r, 1), low_byte);
    const int ones = bits8(_mm256_cmpeq_epi32(region, one));
    int ok = bits8(_mm256_cmpgt_epi32(r, before)) & ~bits8(_mm256_cmpeq_epi32(region, zero)) & (stored ? 0xFF : ones);
    if (stored) {
      const double* f = s.F + 4 * static_cast<std::ptrdiff_t>(k);
      ok &= lambda_bits<B>(lambdas(f)) | lambda_bits<B>(lambdas(f + 16)) << 4;
    } else {
      ok &= lambda_bits<B>(_mm256_set1_pd(s.F[0])) * 0x11;
    }
    if (ok != 0xFF) return false;
    s.prev = s.rows[k + 7];
    if constexpr (kCentroid) {
      for (int m = ones; m != 0; m &= m - 1) {
        const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(s.rows[k + static_cast<std::size_t>(__builtin_ctz(m))]);
        sx += s.P[o] - s.rx;
        sy += s.P[o + 1] - s.ry;
        sz += s.P[o + 2] - s.rz;
      }
      s.ones += static_cast<std::size_t>(__builtin_popcount(ones));
    }
  }
  s.sx = sx, s.sy = sy, s.sz = sz;
  return scan_rows_from<B, kCentroid>(s, k);
}

template <bool kCentroid>
ScanFn pick_scan(Blend blend) {
  switch (blend) {
    case Blend::Smooth: return scan_avx2<Blend::Smooth, kCentroid>;
    case Blend::Quadratic: return scan_avx2<Blend::Quadratic, kCentroid>;
    case Blend::Linear: return scan_avx2<Blend::Linear, kCentroid>;
  }
  return nullptr;
}

}  // namespace

ScanFn avx2_scan(Blend blend, bool centroid) { return centroid ? pick_scan<true>(blend) : pick_scan<false>(blend); }
#else
BlockFn avx2_block(Blend, bool, bool) { return nullptr; }
ScanFn avx2_scan(Blend, bool) { return nullptr; }
#endif

}  // namespace surfeledit::detail
