// The deformation step's kernel (deformation.cpp, docs/algorithms.md §1): one block of deformable rows moved
// in place, several rows at a time in vector registers. Included by deformation.cpp (SSE2 pairs, the
// baseline) and deformation_avx2.cpp (AVX2, four rows, built with -mavx2): each keeps its own copy of the
// kernel (an unnamed namespace), so no AVX code can stand in for the baseline's at link time. Both are built
// without contraction into fused multiply-adds, so both give the same bits (test
// DeformationKernels.Avx2MatchesBaselineBitForBit).
#pragma once

#include <cmath>
#include <cstddef>

#include "surfeledit/core/deformation.hpp"

namespace surfeledit::detail {

constexpr int kStepBlock = 64;  // rows per block of the step (the unit of the threads' static schedule)

// The step's constants.
struct StepConstants {
  double cx, cy, cz;        // rotation centre c
  double tx, ty, tz;        // translation t
  double ax, ay, az;        // unit axis a
  double alpha;             // angle, radians
  double axtx, axty, axtz;  // a x t
  double adt;               // a . t
  double r1[9];             // the whole step's rotation R(a, alpha), row-major (F1 rows: s = 1, g = 0)
  bool small;               // |alpha| <= kNoReduction: sin and cos of s alpha need no range reduction
};

// One block: `count` (<= kStepBlock) rows at positions ks[0..count) of fields.deformable (`rows`), or, when
// `ks` is null, at k0, k0 + 1, ...; F = the first blend row (fields.blend_row(0)), fs = the doubles between
// blend rows (4, or 0 when one constant row stands for all: DeformationFields::blend_stride); P, N, U, V =
// positions, normals, tangents (U and V null without tangents). Returns whether every position and normal it
// wrote is finite (DeformResult::finite).
using BlockFn = bool (*)(const StepConstants&, const Index* rows, const double* F, std::ptrdiff_t fs, const Index* ks,
                         Eigen::Index k0, int count, double* P, double* N, double* U, double* V);

// The AVX2 kernel's block function (deformation_avx2.cpp); null when this build has none.
BlockFn avx2_block(Blend blend, bool rotate, bool tangents);

namespace {
// The step works on several rows at once: D2 is a pair of doubles (one SSE2 register on x86-64), D4 four
// (one AVX register; defined only where AVX is enabled, the AVX2 translation unit); GCC and Clang vector extensions, so
// other targets build too. The same templated code runs on plain doubles for the last rows of a list, with
// the same operations in the same order, so every row's result is the same whichever lane, width or thread
// computes it (no fused multiply-add: the files are built with -ffp-contract=off).
typedef double D2 __attribute__((vector_size(16)));
#if defined(__AVX__)
typedef double D4 __attribute__((vector_size(32)));
#endif

// Lanes of T.
template <class T>
constexpr int kLanes = sizeof(T) / sizeof(double);

inline double splat(double x, double) { return x; }
inline D2 splat(double x, D2) { return D2{x, x}; }
#if defined(__AVX__)
inline D4 splat(double x, D4) { return D4{x, x, x, x}; }
#endif
inline double select(bool m, double a, double b) { return m ? a : b; }
template <class M, class T>
inline T select(M m, T a, T b) { return m ? a : b; }
inline double root(double x) { return std::sqrt(x); }
inline D2 root(D2 x) {
#if defined(__SSE2__)
  return __builtin_ia32_sqrtpd(x);
#else
  return D2{std::sqrt(x[0]), std::sqrt(x[1])};
#endif
}
#if defined(__AVX__)
inline D4 root(D4 x) { return __builtin_ia32_sqrtpd256(x); }
#endif

// sin and cos of x, |x| <= kMaxStepAngle, branch-free: Cody-Waite reduction by pi/2 in three parts (each
// part's product with the quadrant number is exact for |k| < 2^20) and minimax polynomials on
// [-pi/4, pi/4] (fdlibm's kernel coefficients); within about one ulp of the libm values.
// sin_cos_kernel is the polynomial part alone, for |r| <= pi/4 (ps = sin r, pc = cos r).
template <class T>
inline void sin_cos_kernel(T r, T& ps, T& pc) {
  const T z = r * r;
  ps = r + r * z *
                       (-1.66666666666666324348e-01 +
                        z * (8.33333333332248946124e-03 +
                             z * (-1.98412698298579493134e-04 +
                                  z * (2.75573137070700676789e-06 +
                                       z * (-2.50507602534068634195e-08 + z * 1.58969099521155010221e-10)))));
  pc = 1.0 - 0.5 * z +
               z * z *
                   (4.16666666666666019037e-02 +
                    z * (-1.38888888888741095749e-03 +
                         z * (2.48015872894767294178e-05 +
                              z * (-2.75573143513906633035e-07 +
                                   z * (2.08757232129817482790e-09 + z * -1.13596475577881948265e-11)))));
}
// Every |x| <= kNoReduction has quadrant number k = 0 below (|x 2 / pi| < 1/2), where the reduction leaves x
// as it is (x - 0 = x) and the quadrant selects keep (ps, pc): sin_cos_kernel(x) gives the same bits.
constexpr double kNoReduction = 0.78;
template <class T>
inline void sin_cos(T x, T& sn, T& cs) {
  constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  constexpr double kPio2a = 1.57079632673412561417e+00;  // first 33 bits of pi/2
  constexpr double kPio2b = 6.07710050630396597660e-11;  // next 33 bits
  constexpr double kPio2c = 2.02226624871116645580e-21;  // the rest
  constexpr double kRound = 6755399441055744.0;          // 1.5 * 2^52: adding it rounds to an integer
  const T k = (x * kTwoOverPi + kRound) - kRound;        // nearest quadrant number
  const T r = ((x - k * kPio2a) - k * kPio2b) - k * kPio2c;
  T ps, pc;
  sin_cos_kernel(r, ps, pc);
  // Quadrant q = k mod 4 (k is an integer; k / 4 - 0.375 rounds to floor(k / 4) without ties).
  const T q = k - 4.0 * ((k * 0.25 - 0.375 + kRound) - kRound);
  const auto odd = (q == 1.0) | (q == 3.0);
  const T s0 = select(odd, pc, ps), c0 = select(odd, ps, pc);
  sn = select(q >= 2.0, -s0, s0);
  cs = select((q == 1.0) | (q == 2.0), -c0, c0);
}

// Lanes of one call: the rows' offsets into the #P by 3 arrays (3 * row) and into the blend rows (4 * k).
inline double gather(const double* a, const std::ptrdiff_t* o, double) { return a[o[0]]; }
inline D2 gather(const double* a, const std::ptrdiff_t* o, D2) { return D2{a[o[0]], a[o[1]]}; }
#if defined(__AVX__)
inline D4 gather(const double* a, const std::ptrdiff_t* o, D4) { return D4{a[o[0]], a[o[1]], a[o[2]], a[o[3]]}; }
#endif
inline void scatter(double* a, const std::ptrdiff_t* o, double v) { a[o[0]] = v; }
template <class T>
inline void scatter(double* a, const std::ptrdiff_t* o, T v) {
  for (int i = 0; i < kLanes<T>; ++i) a[o[i]] = v[i];
}
// The sum of the lanes (NaN when one is).
inline double lane_sum(double x) { return x; }
template <class T>
inline double lane_sum(T x) {
  double out = 0.0;
  for (int i = 0; i < kLanes<T>; ++i) out += x[i];
  return out;
}
// 0 when x, y and z are finite, else NaN (x - x is NaN for an infinite or NaN x): summed over what a block
// wrote, one test for all of it.
template <class T>
inline T non_finite(T x, T y, T z) {
  return (x - x) + (y - y) + (z - z);
}
inline bool all(bool m) { return m; }
inline bool all(int m) { return m != 0; }
template <class M>
inline bool all(M m) {
  bool out = true;
  for (int i = 0; i < static_cast<int>(sizeof(M) / sizeof(m[0])); ++i) out = out && m[i];
  return out;
}

// One row (T = double) or one per lane (D2, D4). Per row: J = R (I + w g^T) with g = grad s = beta'(lambda) grad lambda
// and w = R^T dF/ds = alpha (a x (p - c)) + R^T t (R commutes with rotations about a). Hence
//   J x = R (x + w (g . x)),  cofactor(J) n = R ((1 + g . w) n - (w . n) g),
// the latter being J u x J v for an orthonormal tangent frame (u, v) of n.
template <class T, Blend B, bool Rotate, bool Tangents, bool Rigid>
inline void step_rows(const StepConstants& sc, const std::ptrdiff_t* o, const std::ptrdiff_t* f, const double* F,
                      double* P, double* N, double* U, double* V, T& bad) {
  const T z{};
  constexpr int L = kLanes<T>;
  std::ptrdiff_t o1[L], o2[L], f1[L], f2[L], f3[L];
  for (int i = 0; i < L; ++i) o1[i] = o[i] + 1, o2[i] = o[i] + 2, f1[i] = f[i] + 1, f2[i] = f[i] + 2, f3[i] = f[i] + 3;
  const T l = gather(F, f, z);
  T s, d;
  if constexpr (B == Blend::Smooth) {
    const T q = l * (l - 2.0);
    s = q * q;
    d = 4.0 * l * (l - 1.0) * (l - 2.0);
  } else if constexpr (B == Blend::Quadratic) {
    s = l * l;
    d = 2.0 * l;
  } else {
    s = l;
    d = splat(1.0, z);
  }
  const T g0 = d * gather(F, f1, z), g1 = d * gather(F, f2, z), g2 = d * gather(F, f3, z);
  const auto flat = (g0 == 0.0) & (g1 == 0.0) & (g2 == 0.0);  // J = R: a rigid motion, no renormalisation
  T px = gather(P, o, z), py = gather(P, o1, z), pz = gather(P, o2, z);
  // Rigid rows take a cheap path: without rotation a flat row's normal and tangents stay as they are (the
  // general formula leaves them bit-identical: m = n, scale 1); with rotation, F1 rows (Rigid) skip the
  // sin/cos and the renormalisation. Which path a row takes depends on the row alone, never on its lane mate.
  if constexpr (!Rotate) {
    if (all(flat)) {
      const T qx = px + s * sc.tx, qy = py + s * sc.ty, qz = pz + s * sc.tz;
      scatter(P, o, qx), scatter(P, o1, qy), scatter(P, o2, qz);
      bad += non_finite(qx, qy, qz);
      return;
    }
  } else if constexpr (Rigid) {
    // F1 (lambda 1, gradient 0): the step's one rotation, as a rigid motion.
    const double* r = sc.r1;
    const T e0 = px - sc.cx, e1 = py - sc.cy, e2 = pz - sc.cz;
    const T qx = r[0] * e0 + r[1] * e1 + r[2] * e2 + sc.cx + sc.tx;
    const T qy = r[3] * e0 + r[4] * e1 + r[5] * e2 + sc.cy + sc.ty;
    const T qz = r[6] * e0 + r[7] * e1 + r[8] * e2 + sc.cz + sc.tz;
    scatter(P, o, qx), scatter(P, o1, qy), scatter(P, o2, qz);
    bad += non_finite(qx, qy, qz);
    for (double* X : {N, U, V}) {
      if (!Tangents && X != N) break;
      const T x0 = gather(X, o, z), x1 = gather(X, o1, z), x2 = gather(X, o2, z);
      const T y0 = r[0] * x0 + r[1] * x1 + r[2] * x2, y1 = r[3] * x0 + r[4] * x1 + r[5] * x2,
              y2 = r[6] * x0 + r[7] * x1 + r[8] * x2;
      scatter(X, o, y0), scatter(X, o1, y1), scatter(X, o2, y2);
      if (X == N) bad += non_finite(y0, y1, y2);
    }
    return;
  }
  // Rotation R = cs I + sn [a]x + (1 - cs) a a^T (identity without rotation), w, new position.
  T w0 = splat(sc.tx, z), w1 = splat(sc.ty, z), w2 = splat(sc.tz, z);
  T r00, r01, r02, r10, r11, r12, r20, r21, r22;
  if constexpr (Rotate) {
    T sn, cs;
    if (sc.small) sin_cos_kernel(s * sc.alpha, sn, cs);  // the same bits as sin_cos there (kNoReduction)
    else sin_cos(s * sc.alpha, sn, cs);
    const T kk = 1.0 - cs;
    const T kxy = kk * (sc.ax * sc.ay), kxz = kk * (sc.ax * sc.az), kyz = kk * (sc.ay * sc.az);
    r00 = cs + kk * (sc.ax * sc.ax), r01 = kxy - sn * sc.az, r02 = kxz + sn * sc.ay;
    r10 = kxy + sn * sc.az, r11 = cs + kk * (sc.ay * sc.ay), r12 = kyz - sn * sc.ax;
    r20 = kxz - sn * sc.ay, r21 = kyz + sn * sc.ax, r22 = cs + kk * (sc.az * sc.az);
    const T e0 = px - sc.cx, e1 = py - sc.cy, e2 = pz - sc.cz;
    px = r00 * e0 + r01 * e1 + r02 * e2 + sc.cx + s * sc.tx;
    py = r10 * e0 + r11 * e1 + r12 * e2 + sc.cy + s * sc.ty;
    pz = r20 * e0 + r21 * e1 + r22 * e2 + sc.cz + s * sc.tz;
    // R^T t = cos t - sin (a x t) + (1 - cos)(a . t) a
    const T ka = kk * sc.adt;
    w0 = sc.alpha * (sc.ay * e2 - sc.az * e1) + (cs * sc.tx - sn * sc.axtx + ka * sc.ax);
    w1 = sc.alpha * (sc.az * e0 - sc.ax * e2) + (cs * sc.ty - sn * sc.axty + ka * sc.ay);
    w2 = sc.alpha * (sc.ax * e1 - sc.ay * e0) + (cs * sc.tz - sn * sc.axtz + ka * sc.az);
  } else {
    px += s * sc.tx, py += s * sc.ty, pz += s * sc.tz;
  }
  scatter(P, o, px), scatter(P, o1, py), scatter(P, o2, pz);
  bad += non_finite(px, py, pz);
  const T n0 = gather(N, o, z), n1 = gather(N, o1, z), n2 = gather(N, o2, z);
  const T gw = 1.0 + (g0 * w0 + g1 * w1 + g2 * w2), wn = w0 * n0 + w1 * n1 + w2 * n2;
  T m0 = gw * n0 - wn * g0, m1 = gw * n1 - wn * g1, m2 = gw * n2 - wn * g2;
  T len2 = m0 * m0 + m1 * m1 + m2 * m2;
  // Both sides of every select are computed: no branches.
  const T nn = n0 * n0 + n1 * n1 + n2 * n2;
  const auto ok = len2 > 0.0;
  m0 = select(ok, m0, n0), m1 = select(ok, m1, n1), m2 = select(ok, m2, n2);
  len2 = select(ok, len2, nn);
  // |R m| = |m|: normalise with m's length; the sign makes the normal agree with R n.
  const T sign = select((m0 * n0 + m1 * n1 + m2 * n2) < 0.0, splat(-1.0, z), splat(1.0, z));
  const T scale = select(flat, splat(1.0, z), sign / root(len2));
  if constexpr (Rotate) {
    const T y0 = scale * (r00 * m0 + r01 * m1 + r02 * m2), y1 = scale * (r10 * m0 + r11 * m1 + r12 * m2),
            y2 = scale * (r20 * m0 + r21 * m1 + r22 * m2);
    scatter(N, o, y0), scatter(N, o1, y1), scatter(N, o2, y2);
    bad += non_finite(y0, y1, y2);
  } else {
    const T y0 = scale * m0, y1 = scale * m1, y2 = scale * m2;
    scatter(N, o, y0), scatter(N, o1, y1), scatter(N, o2, y2);
    bad += non_finite(y0, y1, y2);
  }
  if constexpr (Tangents) {
    for (double* X : {U, V}) {
      const T x0 = gather(X, o, z), x1 = gather(X, o1, z), x2 = gather(X, o2, z);
      const T gx = g0 * x0 + g1 * x1 + g2 * x2;
      const T a0 = x0 + gx * w0, a1 = x1 + gx * w1, a2 = x2 + gx * w2;
      if constexpr (Rotate) {
        scatter(X, o, r00 * a0 + r01 * a1 + r02 * a2);
        scatter(X, o1, r10 * a0 + r11 * a1 + r12 * a2);
        scatter(X, o2, r20 * a0 + r21 * a1 + r22 * a2);
      } else {
        scatter(X, o, a0), scatter(X, o1, a1), scatter(X, o2, a2);
      }
    }
  }
}

// The rows ks[j], ks[j + 1], ... of a list of `count`, kLanes<T> at a time from `j` on while there are that
// many left; returns the first row not done. Adds non_finite() of what it wrote to `bad`.
template <class T, Blend B, bool Rotate, bool Tangents, bool Rigid>
int step_lanes(const StepConstants& sc, const Index* rows, const double* F, std::ptrdiff_t fs, const std::ptrdiff_t* ks,
               int j, int count, double* P, double* N, double* U, double* V, double& bad) {
  constexpr int L = kLanes<T>;
  T acc{};
  for (; j + L <= count; j += L) {
    std::ptrdiff_t o[L], f[L];
    for (int i = 0; i < L; ++i) o[i] = 3 * static_cast<std::ptrdiff_t>(rows[ks[j + i]]), f[i] = fs * ks[j + i];
    step_rows<T, B, Rotate, Tangents, Rigid>(sc, o, f, F, P, N, U, V, acc);
  }
  bad += lane_sum(acc);
  return j;
}

// One block of `count` (<= kStepBlock) rows, W (2 or 4) at a time, then pairs, then single rows. `ks` lists
// the rows' positions in fields.deformable.
template <class W, Blend B, bool Rotate, bool Tangents, bool Rigid>
void step_list(const StepConstants& sc, const Index* rows, const double* F, std::ptrdiff_t fs, const std::ptrdiff_t* ks,
               int count, double* P, double* N, double* U, double* V, double& bad) {
  int j = step_lanes<W, B, Rotate, Tangents, Rigid>(sc, rows, F, fs, ks, 0, count, P, N, U, V, bad);
  if constexpr (kLanes<W> > 2)
    j = step_lanes<D2, B, Rotate, Tangents, Rigid>(sc, rows, F, fs, ks, j, count, P, N, U, V, bad);
  step_lanes<double, B, Rotate, Tangents, Rigid>(sc, rows, F, fs, ks, j, count, P, N, U, V, bad);
}

// One block of `count` (<= kStepBlock) rows, W at a time; with rotation, F1 rows (lambda 1, gradient 0) and
// the others in separate lists. `ks` lists the rows' positions in fields.deformable, or is null for the
// consecutive positions k0, k0 + 1, ...
template <class W, Blend B, bool Rotate, bool Tangents>
bool step_block(const StepConstants& sc, const Index* rows, const double* F, std::ptrdiff_t fs, const Index* ks,
                Eigen::Index k0, int count, double* P, double* N, double* U, double* V) {
  std::ptrdiff_t general[kStepBlock], rigid[kStepBlock];
  int ng = 0, nr = 0;
  for (int j = 0; j < count; ++j) {
    const std::ptrdiff_t k = ks ? ks[j] : k0 + j;
    const double* f = F + fs * k;
    const bool one = Rotate && f[0] == 1.0 && f[1] == 0.0 && f[2] == 0.0 && f[3] == 0.0;
    if (one) rigid[nr++] = k;
    else general[ng++] = k;
  }
  double bad = 0.0;
  step_list<W, B, Rotate, Tangents, false>(sc, rows, F, fs, general, ng, P, N, U, V, bad);
  if (nr > 0) step_list<W, B, Rotate, Tangents, true>(sc, rows, F, fs, rigid, nr, P, N, U, V, bad);
  return bad == 0.0;
}

template <class W, Blend B>
BlockFn pick_block(bool rotate, bool tangents) {
  if (rotate) return tangents ? step_block<W, B, true, true> : step_block<W, B, true, false>;
  return tangents ? step_block<W, B, false, true> : step_block<W, B, false, false>;
}

// The block function of a step for one vector width W.
template <class W>
BlockFn pick_block(Blend blend, bool rotate, bool tangents) {
  switch (blend) {
    case Blend::Smooth: return pick_block<W, Blend::Smooth>(rotate, tangents);
    case Blend::Quadratic: return pick_block<W, Blend::Quadratic>(rotate, tangents);
    case Blend::Linear: return pick_block<W, Blend::Linear>(rotate, tangents);
  }
  return nullptr;
}
}  // namespace
}  // namespace surfeledit::detail
