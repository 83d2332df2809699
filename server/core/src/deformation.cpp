// Deformation tool (docs/algorithms.md §1): blend fields from nearest-neighbour distances to F0 and F1, and
// one step F(p, s) = R(a, s alpha)(p - c) + c + s t applied to positions, normals and tangent axes.
#include "surfeledit/core/deformation.hpp"

#include <omp.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

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
  for (std::size_t k = 0; k < deformable.size(); ++k) out[deformable[k]] = blend(static_cast<Eigen::Index>(k), 0);
  return out;
}

Points DeformationFields::grad_lambda() const {
  Points out = Points::Zero(static_cast<Eigen::Index>(regions.size()), 3);
  for (std::size_t k = 0; k < deformable.size(); ++k)
    out.row(deformable[k]) = blend.block<1, 3>(static_cast<Eigen::Index>(k), 1);
  return out;
}

double DeformationFields::lambda_of(Index row) const {
  const auto it = std::lower_bound(deformable.begin(), deformable.end(), row);
  if (it == deformable.end() || *it != row) return 0.0;
  return blend(static_cast<Eigen::Index>(it - deformable.begin()), 0);
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
  fields.blend.setZero(nd, 4);
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
      fields.blend(k, 0) = 1.0;  // lambda 1, gradient 0
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

// The step works on two rows at once: D2 is a pair of doubles (one SSE2 register on x86-64; GCC and Clang
// vector extensions elsewhere), M2 the mask a comparison of two pairs gives. The same templated code runs on
// plain doubles for an odd last row, with the same operations in the same order, so every row's result is
// the same whichever lane (or thread) computes it.
typedef double D2 __attribute__((vector_size(16)));

inline double splat(double x, double) { return x; }
inline D2 splat(double x, D2) { return D2{x, x}; }
inline double select(bool m, double a, double b) { return m ? a : b; }
template <class M>
inline D2 select(M m, D2 a, D2 b) { return m ? a : b; }
inline double root(double x) { return std::sqrt(x); }
inline D2 root(D2 x) {
#if defined(__SSE2__)
  return __builtin_ia32_sqrtpd(x);
#else
  return D2{std::sqrt(x[0]), std::sqrt(x[1])};
#endif
}

// sin and cos of x, |x| <= kMaxStepAngle, branch-free: Cody-Waite reduction by pi/2 in three parts (each
// part's product with the quadrant number is exact for |k| < 2^20) and minimax polynomials on
// [-pi/4, pi/4] (fdlibm's kernel coefficients); within about one ulp of the libm values.
template <class T>
inline void sin_cos(T x, T& sn, T& cs) {
  constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  constexpr double kPio2a = 1.57079632673412561417e+00;  // first 33 bits of pi/2
  constexpr double kPio2b = 6.07710050630396597660e-11;  // next 33 bits
  constexpr double kPio2c = 2.02226624871116645580e-21;  // the rest
  constexpr double kRound = 6755399441055744.0;          // 1.5 * 2^52: adding it rounds to an integer
  const T k = (x * kTwoOverPi + kRound) - kRound;        // nearest quadrant number
  const T r = ((x - k * kPio2a) - k * kPio2b) - k * kPio2c;
  const T z = r * r;
  const T ps = r + r * z *
                       (-1.66666666666666324348e-01 +
                        z * (8.33333333332248946124e-03 +
                             z * (-1.98412698298579493134e-04 +
                                  z * (2.75573137070700676789e-06 +
                                       z * (-2.50507602534068634195e-08 + z * 1.58969099521155010221e-10)))));
  const T pc = 1.0 - 0.5 * z +
               z * z *
                   (4.16666666666666019037e-02 +
                    z * (-1.38888888888741095749e-03 +
                         z * (2.48015872894767294178e-05 +
                              z * (-2.75573143513906633035e-07 +
                                   z * (2.08757232129817482790e-09 + z * -1.13596475577881948265e-11)))));
  // Quadrant q = k mod 4 (k is an integer; k / 4 - 0.375 rounds to floor(k / 4) without ties).
  const T q = k - 4.0 * ((k * 0.25 - 0.375 + kRound) - kRound);
  const auto odd = (q == 1.0) | (q == 3.0);
  const T s0 = select(odd, pc, ps), c0 = select(odd, ps, pc);
  sn = select(q >= 2.0, -s0, s0);
  cs = select((q == 1.0) | (q == 2.0), -c0, c0);
}

constexpr int kBlock = 64;  // rows per block of the step (the unit of the threads' static schedule)

// The step's constants.
struct StepConstants {
  double cx, cy, cz;     // rotation centre c
  double tx, ty, tz;     // translation t
  double ax, ay, az;     // unit axis a
  double alpha;          // angle, radians
  double axtx, axty, axtz;  // a x t
  double adt;            // a . t
  double r1[9];          // the whole step's rotation R(a, alpha), row-major (F1 rows: s = 1, g = 0)
};

// Lanes of one call: the rows' offsets into the #P by 3 arrays (3 * row) and into the blend rows (4 * k).
inline double gather(const double* a, const std::ptrdiff_t* o, double) { return a[o[0]]; }
inline D2 gather(const double* a, const std::ptrdiff_t* o, D2) { return D2{a[o[0]], a[o[1]]}; }
inline void scatter(double* a, const std::ptrdiff_t* o, double v) { a[o[0]] = v; }
inline void scatter(double* a, const std::ptrdiff_t* o, D2 v) { a[o[0]] = v[0], a[o[1]] = v[1]; }
inline bool all(bool m) { return m; }
inline bool all(int m) { return m != 0; }
template <class M>
inline bool all(M m) {
  return m[0] && m[1];
}

// One or two rows (T = double or D2). Per row: J = R (I + w g^T) with g = grad s = beta'(lambda) grad lambda
// and w = R^T dF/ds = alpha (a x (p - c)) + R^T t (R commutes with rotations about a). Hence
//   J x = R (x + w (g . x)),  cofactor(J) n = R ((1 + g . w) n - (w . n) g),
// the latter being J u x J v for an orthonormal tangent frame (u, v) of n.
template <class T, Blend B, bool Rotate, bool Tangents, bool Rigid>
inline void step_rows(const StepConstants& sc, const std::ptrdiff_t* o, const std::ptrdiff_t* f, const double* F,
                      double* P, double* N, double* U, double* V) {
  const T z{};
  std::ptrdiff_t o1[2], o2[2], f1[2], f2[2], f3[2];
  for (int i = 0; i < 2; ++i) o1[i] = o[i] + 1, o2[i] = o[i] + 2, f1[i] = f[i] + 1, f2[i] = f[i] + 2, f3[i] = f[i] + 3;
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
      scatter(P, o, px + s * sc.tx), scatter(P, o1, py + s * sc.ty), scatter(P, o2, pz + s * sc.tz);
      return;
    }
  } else if constexpr (Rigid) {
    // F1 (lambda 1, gradient 0): the step's one rotation, as a rigid motion.
    const double* r = sc.r1;
    const T e0 = px - sc.cx, e1 = py - sc.cy, e2 = pz - sc.cz;
    scatter(P, o, r[0] * e0 + r[1] * e1 + r[2] * e2 + sc.cx + sc.tx);
    scatter(P, o1, r[3] * e0 + r[4] * e1 + r[5] * e2 + sc.cy + sc.ty);
    scatter(P, o2, r[6] * e0 + r[7] * e1 + r[8] * e2 + sc.cz + sc.tz);
    for (double* X : {N, U, V}) {
      if (!Tangents && X != N) break;
      const T x0 = gather(X, o, z), x1 = gather(X, o1, z), x2 = gather(X, o2, z);
      scatter(X, o, r[0] * x0 + r[1] * x1 + r[2] * x2);
      scatter(X, o1, r[3] * x0 + r[4] * x1 + r[5] * x2);
      scatter(X, o2, r[6] * x0 + r[7] * x1 + r[8] * x2);
    }
    return;
  }
  // Rotation R = cs I + sn [a]x + (1 - cs) a a^T (identity without rotation), w, new position.
  T w0 = splat(sc.tx, z), w1 = splat(sc.ty, z), w2 = splat(sc.tz, z);
  T r00, r01, r02, r10, r11, r12, r20, r21, r22;
  if constexpr (Rotate) {
    T sn, cs;
    sin_cos(s * sc.alpha, sn, cs);
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
    scatter(N, o, scale * (r00 * m0 + r01 * m1 + r02 * m2));
    scatter(N, o1, scale * (r10 * m0 + r11 * m1 + r12 * m2));
    scatter(N, o2, scale * (r20 * m0 + r21 * m1 + r22 * m2));
  } else {
    scatter(N, o, scale * m0), scatter(N, o1, scale * m1), scatter(N, o2, scale * m2);
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

// One block of `count` (<= kBlock) rows, two at a time. `ks` lists the rows' positions in
// fields.deformable, or is null for the consecutive positions k0, k0 + 1, ...
template <Blend B, bool Rotate, bool Tangents, bool Rigid>
void step_list(const StepConstants& sc, const Index* rows, const double* F, const std::ptrdiff_t* ks, int count,
               double* P, double* N, double* U, double* V) {
  int j = 0;
  for (; j + 1 < count; j += 2) {
    const std::ptrdiff_t o[2] = {3 * static_cast<std::ptrdiff_t>(rows[ks[j]]), 3 * static_cast<std::ptrdiff_t>(rows[ks[j + 1]])};
    const std::ptrdiff_t f[2] = {4 * ks[j], 4 * ks[j + 1]};
    step_rows<D2, B, Rotate, Tangents, Rigid>(sc, o, f, F, P, N, U, V);
  }
  if (j < count) {
    const std::ptrdiff_t o[2] = {3 * static_cast<std::ptrdiff_t>(rows[ks[j]]), 0};
    const std::ptrdiff_t f[2] = {4 * ks[j], 0};
    step_rows<double, B, Rotate, Tangents, Rigid>(sc, o, f, F, P, N, U, V);
  }
}

// One block of `count` (<= kBlock) rows, two at a time; with rotation, F1 rows (lambda 1, gradient 0) and
// the others in separate lists. `ks` lists the rows' positions in fields.deformable, or is null for the
// consecutive positions k0, k0 + 1, ...
template <Blend B, bool Rotate, bool Tangents>
void step_block(const StepConstants& sc, const Index* rows, const double* F, const Index* ks, Eigen::Index k0,
                int count, double* P, double* N, double* U, double* V) {
  std::ptrdiff_t general[kBlock], rigid[kBlock];
  int ng = 0, nr = 0;
  for (int j = 0; j < count; ++j) {
    const std::ptrdiff_t k = ks ? ks[j] : k0 + j;
    const double* f = F + 4 * k;
    const bool one = Rotate && f[0] == 1.0 && f[1] == 0.0 && f[2] == 0.0 && f[3] == 0.0;
    if (one) rigid[nr++] = k;
    else general[ng++] = k;
  }
  step_list<B, Rotate, Tangents, false>(sc, rows, F, general, ng, P, N, U, V);
  if (nr > 0) step_list<B, Rotate, Tangents, true>(sc, rows, F, rigid, nr, P, N, U, V);
}

using BlockFn = void (*)(const StepConstants&, const Index*, const double*, const Index*, Eigen::Index, int, double*,
                         double*, double*, double*);

template <Blend B>
BlockFn pick_block(bool rotate, bool tangents) {
  if (rotate) return tangents ? step_block<B, true, true> : step_block<B, true, false>;
  return tangents ? step_block<B, false, true> : step_block<B, false, false>;
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
    const double l = fields.blend(static_cast<Eigen::Index>(k), 0);
    if (region == Region::Zero || !(l >= 0.0 && l <= 1.0)) {
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

}  // namespace

DeformResult apply_step(const DeformationFields& fields, const DeformParams& params, Points& positions,
                        Points& normals, Points* tangent_u, Points* tangent_v, int threads, const IndexList* only) {
  // ---- validation: nothing below this block may throw after an array was written ----
  validate(params, fields);
  const int nthreads = checked_threads(threads, "threads");
  const Eigen::Index n = positions.rows();
  auto require_rows = [n](Eigen::Index rows, const char* field) {
    if (rows != n) {
      throw Error(ErrorCode::InvalidArgument, field,
                  "has " + std::to_string(rows) + " rows but positions have " + std::to_string(n));
    }
  };
  require_rows(static_cast<Eigen::Index>(fields.regions.size()), "fields.regions");
  if (fields.blend.rows() != static_cast<Eigen::Index>(fields.deformable.size())) {
    throw Error(ErrorCode::InvalidArgument, "fields.blend",
                "has " + std::to_string(fields.blend.rows()) + " rows but fields.deformable lists " +
                    std::to_string(fields.deformable.size()));
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
  const std::size_t listed = only ? only_ks.size() : fields.deformable.size();
  result.moved.reserve(listed);
  IndexList ks;  // positions in fields.deformable of the moved rows
  ks.reserve(listed);
  Vec3 f1_ref = Vec3::Zero(), f1_sum = Vec3::Zero();
  std::size_t f1_count = 0;
  const bool need_centroid = !params.center;
  const IndexList* ks_in = only ? &only_ks : nullptr;
  switch (params.blend) {
    case Blend::Smooth:
      scan_rows<Blend::Smooth>(fields, ks_in, n, need_centroid, result, ks, f1_ref, f1_sum, f1_count, positions.data());
      break;
    case Blend::Quadratic:
      scan_rows<Blend::Quadratic>(fields, ks_in, n, need_centroid, result, ks, f1_ref, f1_sum, f1_count,
                                  positions.data());
      break;
    case Blend::Linear:
      scan_rows<Blend::Linear>(fields, ks_in, n, need_centroid, result, ks, f1_ref, f1_sum, f1_count, positions.data());
      break;
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
  StepConstants sc{c.x(), c.y(), c.z(), t.x(), t.y(), t.z(), a.x(), a.y(), a.z(), params.angle,
                   axt.x(), axt.y(), axt.z(), a.dot(t), {}};
  {  // Rodrigues: R = cs I + sn [a]x + (1 - cs) a a^T
    const double cs = std::cos(params.angle), sn = std::sin(params.angle), k = 1.0 - cs;
    const double kxy = k * a.x() * a.y(), kxz = k * a.x() * a.z(), kyz = k * a.y() * a.z();
    const double r1[9] = {cs + k * a.x() * a.x(), kxy - sn * a.z(), kxz + sn * a.y(),
                          kxy + sn * a.z(), cs + k * a.y() * a.y(), kyz - sn * a.x(),
                          kxz - sn * a.y(), kyz + sn * a.x(), cs + k * a.z() * a.z()};
    std::copy(r1, r1 + 9, sc.r1);
  }
  BlockFn block = nullptr;
  switch (params.blend) {
    case Blend::Smooth: block = pick_block<Blend::Smooth>(rotate, has_u); break;
    case Blend::Quadratic: block = pick_block<Blend::Quadratic>(rotate, has_u); break;
    case Blend::Linear: block = pick_block<Blend::Linear>(rotate, has_u); break;
  }
  // Every listed row moves (the usual case): blocks of consecutive positions, no index list.
  const bool consecutive = !only && ks.size() == fields.deformable.size();
  const Eigen::Index n_moved = static_cast<Eigen::Index>(ks.size());
  const Eigen::Index n_blocks = (n_moved + kBlock - 1) / kBlock;
  const Index* rows = fields.deformable.data();
  const double* F = fields.blend.data();
  double* P = positions.data();
  double* N = normals.data();
  double* U = has_u ? tangent_u->data() : nullptr;
  double* V = has_v ? tangent_v->data() : nullptr;
  auto run = [&](Eigen::Index b) {
    const Eigen::Index k0 = b * kBlock;
    const int count = static_cast<int>(std::min<Eigen::Index>(kBlock, n_moved - k0));
    block(sc, rows, F, consecutive ? nullptr : ks.data() + k0, k0, count, P, N, U, V);
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

}  // namespace surfeledit
