// The k-d tree's leaf scans four points at a time and the walk's box tests on three axes at once (AVX2;
// kdtree_search.hpp, kdtree_walk.hpp). This file alone is built with
// -mavx2 and without fused multiply-adds, so every lane computes dx * dx + dy * dy + dz * dz exactly as the
// scalar scan does and the winners are bit-identical; KdTree uses it only on a CPU that has AVX2
// (kd_scan_available). The scan type has internal linkage, so the descent instantiated here (Descent<Avx2Scan,
// .>) is this file's own; the shared helpers it inlines (the sets' add / worst) are forced inline, so no AVX
// copy of them can stand in for the baseline's at link time.
// kdtree_avx512.cpp builds this file again for AVX-512VL under another entry name (SURFELEDIT_KD_ENTRY).
#include "kdtree_walk.hpp"

#include <cstring>

#if defined(__AVX2__) && !defined(__FMA__)
#include <immintrin.h>
#endif

#ifndef SURFELEDIT_KD_ENTRY
#define SURFELEDIT_KD_ENTRY avx2_search
#endif

namespace surfeledit::kd {

#if defined(__AVX2__) && !defined(__FMA__)
namespace {

// kLanes[r]: the first r of 4 lanes set (a leaf's last, partial vector; the lanes past the leaf read the next
// leaf's points or the tree's zero tail and are never fed to the set).
alignas(32) constexpr std::int64_t kLanes[5][4] = {
    {0, 0, 0, 0}, {-1, 0, 0, 0}, {-1, -1, 0, 0}, {-1, -1, -1, 0}, {-1, -1, -1, -1}};

struct Avx2Scan {
  struct Query {
    __m256d x, y, z;
    explicit Query(const double* q) : x(_mm256_set1_pd(q[0])), y(_mm256_set1_pd(q[1])), z(_mm256_set1_pd(q[2])) {}
  };
  // dist2 of slots s .. s + 3, summed as the scalar scan sums it.
  static __m256d dist2(const Tree& t, const Query& q, std::uint32_t s) {
    const __m256d dx = _mm256_sub_pd(q.x, _mm256_loadu_pd(t.xs() + s));
    const __m256d dy = _mm256_sub_pd(q.y, _mm256_loadu_pd(t.ys() + s));
    const __m256d dz = _mm256_sub_pd(q.z, _mm256_loadu_pd(t.zs() + s));
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
  }
  static __m256d lanes(std::uint32_t r) {
    return _mm256_castsi256_pd(_mm256_load_si256(reinterpret_cast<const __m256i*>(kLanes[r < 4 ? r : 4])));
  }

  // A compare's lanes (all bits set or clear) as a blend mask, opaque to the compiler: GCC otherwise re-derives
  // the blend's sign-bit test from it with an extra integer compare per blend.
  [[gnu::always_inline]] static __m256d sign_mask(__m256d m) {
    asm("" : "+x"(m));
    return m;
  }

  // The smallest of v's four lanes, in every lane.
  static __m256d lane_min(__m256d v) {
    v = _mm256_min_pd(v, _mm256_permute2f128_pd(v, v, 1));
    return _mm256_min_pd(v, _mm256_permute_pd(v, 5));
  }

  // k = 1: per lane the first strict minimum (slots ascend along a lane; slots are kept as doubles, exact below
  // 2^53), then the smallest dist2 of the lanes and the smallest slot among the lanes holding it: the
  // lexicographic (dist2, slot) minimum, the scalar scan's winner, without a branch. A leaf whose every point is
  // at +inf (overflow) leaves every lane empty; the scalar scan then offers its first point, and so does this one.
  static void nearest(const Tree& t, const double* qp, std::uint32_t a, std::uint32_t b, NearestSet& set) {
#if defined(__AVX512F__)
    nearest8(t, qp, a, b, set);  // the AVX-512 build
#else
    const Query q(qp);
    const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    __m256d best = inf, best_slot = inf;
    __m256d slot = _mm256_setr_pd(a, a + 1.0, a + 2.0, a + 3.0);
    const __m256d four = _mm256_set1_pd(4.0);
    // Blocks of eight points into two independent minima (half the loop's dependency chain), merged lane by lane;
    // then whole vectors of four; the lane mask only for the last, partial vector. The same winner as one pass.
    std::uint32_t s = a;
    if (b - a >= 8) {
      __m256d best1 = inf, best_slot1 = inf;
      __m256d slot1 = _mm256_add_pd(slot, four);
      const __m256d eight = _mm256_set1_pd(8.0);
      for (; s + 8 <= b; s += 8) {
        const __m256d d0 = dist2(t, q, s), d1 = dist2(t, q, s + 4);
        const __m256d lt0 = sign_mask(_mm256_cmp_pd(d0, best, _CMP_LT_OQ));
        const __m256d lt1 = sign_mask(_mm256_cmp_pd(d1, best1, _CMP_LT_OQ));
        best = _mm256_min_pd(d0, best);  // d0 < best ? d0 : best, per lane: the blend by lt0
        best_slot = _mm256_blendv_pd(best_slot, slot, lt0);
        best1 = _mm256_min_pd(d1, best1);
        best_slot1 = _mm256_blendv_pd(best_slot1, slot1, lt1);
        slot = _mm256_add_pd(slot, eight);
        slot1 = _mm256_add_pd(slot1, eight);
      }
      // Lane by lane the (dist2, slot)-smaller of the two.
      const __m256d take1 = _mm256_or_pd(_mm256_cmp_pd(best1, best, _CMP_LT_OQ),
                                         _mm256_and_pd(_mm256_cmp_pd(best1, best, _CMP_EQ_OQ),
                                                       _mm256_cmp_pd(best_slot1, best_slot, _CMP_LT_OQ)));
      best = _mm256_blendv_pd(best, best1, take1);
      best_slot = _mm256_blendv_pd(best_slot, best_slot1, take1);
    }
    for (; s + 4 <= b; s += 4) {
      const __m256d d2 = dist2(t, q, s);
      const __m256d lt = sign_mask(_mm256_cmp_pd(d2, best, _CMP_LT_OQ));
      best = _mm256_min_pd(d2, best);
      best_slot = _mm256_blendv_pd(best_slot, slot, lt);
      slot = _mm256_add_pd(slot, four);
    }
    if (s < b) {
      const __m256d d2 = dist2(t, q, s);
      const __m256d lt = _mm256_and_pd(_mm256_cmp_pd(d2, best, _CMP_LT_OQ), lanes(b - s));
      best = _mm256_blendv_pd(best, d2, lt);
      best_slot = _mm256_blendv_pd(best_slot, slot, lt);
    }
    const __m256d m = lane_min(best);
    const __m256d k = lane_min(_mm256_blendv_pd(inf, best_slot, _mm256_cmp_pd(best, m, _CMP_EQ_OQ)));
    const double ks = _mm256_cvtsd_f64(k);
    set.add(_mm256_cvtsd_f64(m), ks < std::numeric_limits<double>::infinity() ? static_cast<std::uint32_t>(ks) : a);
#endif
  }

#if defined(__AVX512F__)
  // nearest() eight points at a time (the AVX-512 build): the same per-lane first strict minimum and the same
  // (dist2, slot) choice among the lanes; the last, partial vector's loads and compares masked. A leaf of sixteen
  // points or more goes to nearest16() (out of line, so the short leaves of other trees keep this loop's code).
  static void nearest8(const Tree& t, const double* qp, std::uint32_t a, std::uint32_t b, NearestSet& set) {
    if (b - a >= 16) return nearest16(t, qp, a, b, set);
    const Lanes8 q(qp, a);
    __m512d best = q.inf, best_slot = q.inf, slot = q.slot;
    scan8(t, q, a, b, best, best_slot, slot);
    offer(best, best_slot, a, set);
  }
  // nearest8() with blocks of sixteen points into two independent minima (half the loop's dependency chain),
  // merged lane by lane with the tie rule (the smaller slot among equal distances), then the rest eight at a time:
  // the same winner as one pass (RESULTS §75).
  [[gnu::noinline]] static void nearest16(const Tree& t, const double* qp, std::uint32_t a, std::uint32_t b,
                                          NearestSet& set) {
    const Lanes8 q(qp, a);
    const __m512d eight = _mm512_set1_pd(8.0), sixteen = _mm512_set1_pd(16.0);
    __m512d best = q.inf, best_slot = q.inf, slot = q.slot;
    __m512d best1 = q.inf, best_slot1 = q.inf, slot1 = _mm512_add_pd(q.slot, eight);
    std::uint32_t s = a;
    for (; s + 16 <= b; s += 16) {
      const __m512d d0 = q.dist2(t, s), d1 = q.dist2(t, s + 8);
      const __mmask8 lt0 = _mm512_cmp_pd_mask(d0, best, _CMP_LT_OQ), lt1 = _mm512_cmp_pd_mask(d1, best1, _CMP_LT_OQ);
      best = _mm512_mask_mov_pd(best, lt0, d0);
      best_slot = _mm512_mask_mov_pd(best_slot, lt0, slot);
      best1 = _mm512_mask_mov_pd(best1, lt1, d1);
      best_slot1 = _mm512_mask_mov_pd(best_slot1, lt1, slot1);
      slot = _mm512_add_pd(slot, sixteen);
      slot1 = _mm512_add_pd(slot1, sixteen);
    }
    const __mmask8 take1 = _mm512_cmp_pd_mask(best1, best, _CMP_LT_OQ) |
                           (_mm512_cmp_pd_mask(best1, best, _CMP_EQ_OQ) & _mm512_cmp_pd_mask(best_slot1, best_slot, _CMP_LT_OQ));
    best = _mm512_mask_mov_pd(best, take1, best1);
    best_slot = _mm512_mask_mov_pd(best_slot, take1, best_slot1);
    scan8(t, q, s, b, best, best_slot, slot);
    offer(best, best_slot, a, set);
  }
  // The query in every lane, +inf and the first slots a .. a + 7 (as doubles).
  struct Lanes8 {
    __m512d x, y, z, inf, slot;
    Lanes8(const double* qp, std::uint32_t a)
        : x(_mm512_set1_pd(qp[0])), y(_mm512_set1_pd(qp[1])), z(_mm512_set1_pd(qp[2])),
          inf(_mm512_set1_pd(std::numeric_limits<double>::infinity())),
          slot(_mm512_add_pd(_mm512_set1_pd(a), _mm512_setr_pd(0, 1, 2, 3, 4, 5, 6, 7))) {}
    // dist2 of slots s .. s + 7 (all in the tree or its tail), summed as the scalar scan sums it.
    [[gnu::always_inline]] __m512d dist2(const Tree& t, std::uint32_t s) const {
      const __m512d dx = _mm512_sub_pd(x, _mm512_loadu_pd(t.xs() + s));
      const __m512d dy = _mm512_sub_pd(y, _mm512_loadu_pd(t.ys() + s));
      const __m512d dz = _mm512_sub_pd(z, _mm512_loadu_pd(t.zs() + s));
      return _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
    }
  };
  // Slots [s, b) into the per-lane minima, eight at a time, the last vector's loads and compares masked.
  [[gnu::always_inline]] static void scan8(const Tree& t, const Lanes8& q, std::uint32_t s, std::uint32_t b, __m512d& best,
                                           __m512d& best_slot, __m512d& slot) {
    const __m512d eight = _mm512_set1_pd(8.0);
    for (; s < b; s += 8) {
      const __mmask8 in = b - s >= 8 ? __mmask8(0xff) : static_cast<__mmask8>((1u << (b - s)) - 1u);
      const __m512d dx = _mm512_sub_pd(q.x, _mm512_maskz_loadu_pd(in, t.xs() + s));
      const __m512d dy = _mm512_sub_pd(q.y, _mm512_maskz_loadu_pd(in, t.ys() + s));
      const __m512d dz = _mm512_sub_pd(q.z, _mm512_maskz_loadu_pd(in, t.zs() + s));
      const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
      const __mmask8 lt = _mm512_mask_cmp_pd_mask(in, d2, best, _CMP_LT_OQ);
      best = _mm512_mask_mov_pd(best, lt, d2);
      best_slot = _mm512_mask_mov_pd(best_slot, lt, slot);
      slot = _mm512_add_pd(slot, eight);
    }
  }
  // The (dist2, slot)-smallest of the lanes' minima to the set (slot a for a leaf whose points are all at +inf).
  [[gnu::always_inline]] static void offer(__m512d best, __m512d best_slot, std::uint32_t a, NearestSet& set) {
    // A leaf none of whose lanes reaches the set's best offers nothing set.add() would take (most leaves of a
    // descent): no reduction across the lanes then.
    if (_mm512_cmp_pd_mask(best, _mm512_set1_pd(set.best), _CMP_LE_OQ) == 0) return;
    const double m = _mm512_reduce_min_pd(best);
    const __mmask8 at_m = _mm512_cmp_pd_mask(best, _mm512_set1_pd(m), _CMP_EQ_OQ);
    // One lane at the minimum (no tie across lanes): its slot, else the smallest of theirs.
    const double ks = (at_m & (at_m - 1)) == 0 ? _mm512_cvtsd_f64(_mm512_maskz_compress_pd(at_m, best_slot))
                                               : _mm512_mask_reduce_min_pd(at_m, best_slot);
    set.add(m, ks < std::numeric_limits<double>::infinity() ? static_cast<std::uint32_t>(ks) : a);
  }
#endif

  // Any other set: the points that could enter it (dist2 <= its worst at the vector's start, which only
  // shrinks), in slot order; add() re-checks each against the worst as it is then, as the scalar scan does.
  template <class Set>
  static void each(const Tree& t, const double* qp, std::uint32_t a, std::uint32_t b, Set& set) {
    const Query q(qp);
    alignas(32) double d[4];
    for (std::uint32_t s = a; s < b; s += 4) {
      const __m256d d2 = dist2(t, q, s);
      const __m256d le = _mm256_and_pd(_mm256_cmp_pd(d2, _mm256_set1_pd(set.worst()), _CMP_LE_OQ), lanes(b - s));
      unsigned bits = static_cast<unsigned>(_mm256_movemask_pd(le));
      if (bits == 0) continue;
      _mm256_store_pd(d, d2);
      for (; bits != 0; bits &= bits - 1) {
        const unsigned i = static_cast<unsigned>(__builtin_ctz(bits));
        set.add(d[i], s + i);
      }
    }
  }
};

// The second block of a fan of at most four lanes: no lane (cells with lo = +inf, hi = -inf).
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr FanBlock kEmptyBlock = {
    {{kInf, kInf, kInf, kInf}, {kInf, kInf, kInf, kInf}, {kInf, kInf, kInf, kInf}},
    {{-kInf, -kInf, -kInf, -kInf}, {-kInf, -kInf, -kInf, -kInf}, {-kInf, -kInf, -kInf, -kInf}},
    {0, 0, 0, 0}};

// The walk's box tests (kdtree_walk.hpp's ScalarWalk) on the three axes at once: the same subtractions, min /
// max, products and (scalar, x + y + z) sum per axis, so the same bits. A cell's six floats are read as lanes
// (lo0, lo1, lo2, hi0) and (hi0, hi1, hi2, lo2) from two 16-byte loads inside the cell (the second, from lo2,
// rotated one lane), so lane 3 is a finite or infinite box coordinate, never the parent word (which, read as a
// float, is a denormal that could cost a microcode assist); q's lane 3 is 0 and lane 3's results are ignored.
class Avx2Walk {
 public:
  static constexpr bool kFans = true;
  // bound() of every used lane of a fan (blocks: its blocks), a block of four lanes at a time: per lane the per-axis
  // offsets (off[axis][lane]) and their sum (bound[lane]), with bound()'s operations; returns the used lanes whose
  // bound is <= best. Both blocks are computed, a fan of one block reading an empty one for its second (a select,
  // not a branch: how many lanes a fan has is not predictable).
  unsigned fan_bounds(const Fan& f, const FanBlock* blocks, double best, double* bound,
                      double (*off)[kFanLanes]) const {
    static_assert(kFanLanes == 2 * kFanBlock, "a fan is two blocks");
#if defined(__AVX512F__)
    // The AVX-512 build: both blocks' lanes in one vector of eight, the same operations per lane.
    const FanBlock* second = f.lanes >> kFanBlock ? blocks + 1 : &kEmptyBlock;
    Lanes lo, hi;
    for (int d = 0; d < 3; ++d) {
      lo[d] = _mm512_cvtps_pd(
          _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(blocks->lo[d])), _mm_load_ps(second->lo[d]), 1));
      hi[d] = _mm512_cvtps_pd(
          _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(blocks->hi[d])), _mm_load_ps(second->hi[d]), 1));
    }
    return lane_bounds(lo, hi, best, bound, off, 0) & f.lanes;
#else
    const FanBlock* block[2] = {blocks, f.lanes >> kFanBlock ? blocks + 1 : &kEmptyBlock};
    unsigned mask = 0;
    for (int h = 0; h < 2; ++h) {
      Lanes lo, hi;
      for (int d = 0; d < 3; ++d) {
        lo[d] = _mm256_cvtps_pd(_mm_load_ps(block[h]->lo[d]));
        hi[d] = _mm256_cvtps_pd(_mm_load_ps(block[h]->hi[d]));
      }
      mask |= lane_bounds(lo, hi, best, bound, off, kFanBlock * h) << (kFanBlock * h);
    }
    return mask & f.lanes;
#endif
  }
  // fan_bounds() of a halo's nodes (blocks: its blocks), their boxes decoded as Halo::value does (the same operations,
  // so the same bits): bound[k] and off[axis][k] for each node k; returns the nodes whose bound is <= best.
  std::uint64_t halo_bounds(const Halo& h, const HaloBlock* blocks, double best, double* bound,
                            double (*off)[kMaxHalo]) const {
    static_assert(kMaxHalo <= 64 && kMaxHalo % kHaloBlock == 0, "a halo's nodes are bits of one word");
    std::uint64_t mask = 0;
#if defined(__AVX512F__)
    __m512d base[3], step[3];
    for (int d = 0; d < 3; ++d) {
      base[d] = _mm512_set1_pd(static_cast<double>(h.reach.lo[d]));
      step[d] = _mm512_set1_pd(Halo::step(h.reach, d));
    }
    auto decode = [&](const std::uint8_t* c, int d) {
      const __m512d v = _mm512_cvtepi32_pd(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(c))));
      return _mm512_add_pd(base[d], _mm512_mul_pd(v, step[d]));
    };
    for (unsigned k = 0; k * kHaloBlock < h.count; ++k) {
      Lanes lo, hi;
      for (int d = 0; d < 3; ++d) {
        lo[d] = decode(blocks[k].lo[d], d);
        hi[d] = decode(blocks[k].hi[d], d);
      }
      mask |= static_cast<std::uint64_t>(lane_bounds(lo, hi, best, bound, off, kHaloBlock * k)) << (kHaloBlock * k);
    }
#else
    __m256d base[3], step[3];
    for (int d = 0; d < 3; ++d) {
      base[d] = _mm256_set1_pd(static_cast<double>(h.reach.lo[d]));
      step[d] = _mm256_set1_pd(Halo::step(h.reach, d));
    }
    auto decode = [&](const std::uint8_t* c, int d) {
      std::int32_t four;
      std::memcpy(&four, c, sizeof four);
      const __m256d v = _mm256_cvtepi32_pd(_mm_cvtepu8_epi32(_mm_cvtsi32_si128(four)));
      return _mm256_add_pd(base[d], _mm256_mul_pd(v, step[d]));
    };
    for (unsigned k = 0; k * 4 < h.count; ++k) {
      const HaloBlock& b = blocks[k / 2];
      const unsigned at = (k % 2) * 4;
      Lanes lo, hi;
      for (int d = 0; d < 3; ++d) {
        lo[d] = decode(b.lo[d] + at, d);
        hi[d] = decode(b.hi[d] + at, d);
      }
      mask |= static_cast<std::uint64_t>(lane_bounds(lo, hi, best, bound, off, 4 * k)) << (4 * k);
    }
#endif
    return h.count >= 64 ? mask : mask & ((std::uint64_t{1} << h.count) - 1);  // unused lanes' codes are 0
  }
  Avx2Walk(const double* q, const double* box)
      : q_(_mm256_setr_pd(q[0], q[1], q[2], 0.0)), box_(_mm256_setr_pd(box[0], box[1], box[2], 0.0)),
        qs_{_mm256_set1_pd(q[0]), _mm256_set1_pd(q[1]), _mm256_set1_pd(q[2])},
        boxes_{_mm256_set1_pd(box[0]), _mm256_set1_pd(box[1]), _mm256_set1_pd(box[2])} {}
  bool holds(const Cell& c, double best) const {
    __m256d lo, hi;
    load(c, lo, hi);
    const __m256d g = _mm256_min_pd(_mm256_sub_pd(q_, lo), _mm256_sub_pd(hi, q_));
    const __m256d in = _mm256_and_pd(_mm256_cmp_pd(g, _mm256_setzero_pd(), _CMP_GT_OQ),
                                     _mm256_cmp_pd(_mm256_mul_pd(g, g), _mm256_set1_pd(best), _CMP_GT_OQ));
    return (_mm256_movemask_pd(in) & 7) == 7;
  }
  double bound(const Cell& c, double* off) const {
    __m256d lo, hi;
    load(c, lo, hi);
    const __m256d g = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(lo, q_), _mm256_sub_pd(q_, hi)), _mm256_setzero_pd());
    _mm256_store_pd(off, _mm256_max_pd(_mm256_mul_pd(g, g), box_));
    return off[0] + off[1] + off[2];
  }

 private:
  static void load(const Cell& c, __m256d& lo, __m256d& hi) {
    lo = _mm256_cvtps_pd(_mm_loadu_ps(c.lo));
    hi = _mm256_cvtps_pd(_mm_permute_ps(_mm_loadu_ps(c.lo + 2), _MM_SHUFFLE(0, 3, 2, 1)));
  }
#if defined(__AVX512F__)
  using Lanes = __m512d[3];  // per axis, one coordinate of eight lanes' boxes
#else
  using Lanes = __m256d[3];  // per axis, one coordinate of four lanes' boxes
#endif
  // bound() of the lanes whose boxes are lo[axis] .. hi[axis]: per lane the per-axis offsets into off[axis][at + lane]
  // and their sum into bound[at + lane], with bound()'s operations (the same bits); returns the lanes <= best.
  template <std::size_t N>
  unsigned lane_bounds(const Lanes& lo, const Lanes& hi, double best, double* bound, double (*off)[N],
                       unsigned at) const {
#if defined(__AVX512F__)
    __m512d o[3];
    for (int d = 0; d < 3; ++d) {
      const __m512d qd = _mm512_broadcast_f64x4(qs_[d]);
      const __m512d g =
          _mm512_max_pd(_mm512_max_pd(_mm512_sub_pd(lo[d], qd), _mm512_sub_pd(qd, hi[d])), _mm512_setzero_pd());
      o[d] = _mm512_max_pd(_mm512_mul_pd(g, g), _mm512_broadcast_f64x4(boxes_[d]));
      _mm512_storeu_pd(off[d] + at, o[d]);
    }
    const __m512d sum = _mm512_add_pd(_mm512_add_pd(o[0], o[1]), o[2]);
    _mm512_storeu_pd(bound + at, sum);
    return static_cast<unsigned>(_mm512_cmp_pd_mask(sum, _mm512_set1_pd(best), _CMP_LE_OQ));
#else
    __m256d o[3];
    for (int d = 0; d < 3; ++d) {
      const __m256d g =
          _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(lo[d], qs_[d]), _mm256_sub_pd(qs_[d], hi[d])), _mm256_setzero_pd());
      o[d] = _mm256_max_pd(_mm256_mul_pd(g, g), boxes_[d]);
      _mm256_storeu_pd(off[d] + at, o[d]);
    }
    const __m256d sum = _mm256_add_pd(_mm256_add_pd(o[0], o[1]), o[2]);
    _mm256_storeu_pd(bound + at, sum);
    return static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(sum, _mm256_set1_pd(best), _CMP_LE_OQ)));
#endif
  }
  __m256d q_, box_;
  __m256d qs_[3], boxes_[3];  // q and the box offsets per axis, in every lane
};

}  // namespace

const SearchFns* SURFELEDIT_KD_ENTRY() {
  static const SearchFns fns = search_fns<Avx2Scan, Avx2Walk>();
  return &fns;
}
#else
const SearchFns* SURFELEDIT_KD_ENTRY() { return nullptr; }
#endif

}  // namespace surfeledit::kd
