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

// Minimal scalar 3-vector and 3x3 matrix for the per-surfel loop of apply_step.
struct V3 {
  double x, y, z;
  static V3 load(const double* p) { return {p[0], p[1], p[2]}; }
  static V3 of(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
  void store(double* p) const {
    p[0] = x;
    p[1] = y;
    p[2] = z;
  }
};
inline V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double k, const V3& a) { return {k * a.x, k * a.y, k * a.z}; }
inline double dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
struct R3 {
  double m[9];  // row-major
  static R3 of(const Mat3& r) {
    R3 o;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) o.m[3 * i + j] = r(i, j);
    return o;
  }
  // Rodrigues: R = cs I + sn [a]x + (1 - cs) a a^T, a unit.
  static R3 rotation(const V3& a, double cs, double sn) {
    const double k = 1.0 - cs;
    const double kxy = k * a.x * a.y, kxz = k * a.x * a.z, kyz = k * a.y * a.z;
    return {{cs + k * a.x * a.x, kxy - sn * a.z, kxz + sn * a.y,  //
             kxy + sn * a.z, cs + k * a.y * a.y, kyz - sn * a.x,  //
             kxz - sn * a.y, kyz + sn * a.x, cs + k * a.z * a.z}};
  }
  V3 operator*(const V3& v) const {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
            m[6] * v.x + m[7] * v.y + m[8] * v.z};
  }
  V3 transposed_times(const V3& v) const {
    return {m[0] * v.x + m[3] * v.y + m[6] * v.z, m[1] * v.x + m[4] * v.y + m[7] * v.z,
            m[2] * v.x + m[5] * v.y + m[8] * v.z};
  }
};

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

std::size_t DeformationFields::memory_bytes() const {
  return regions.capacity() * sizeof(Region) + static_cast<std::size_t>(lambda.size()) * sizeof(double) +
         static_cast<std::size_t>(grad_lambda.size()) * sizeof(double) + deformable.capacity() * sizeof(Index);
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

  fields.lambda.setZero(n);
  fields.grad_lambda.setZero(n, 3);
  Index conflict = std::numeric_limits<Index>::max();
  // Every row is checked against the region it is not in (F0 rows against F1 too), so a surfel
  // lying in both (d0 + d1 == 0) is reported whatever its label.
#pragma omp parallel for schedule(static) num_threads(nthreads) reduction(min : conflict)
  for (Eigen::Index i = 0; i < n; ++i) {
    const Region r = regions[static_cast<std::size_t>(i)];
    const Vec3 p = positions.row(i).transpose();
    // Offsets to the nearest F0 / F1 surfel (model units) and their real (not squared) lengths.
    Vec3 e0 = Vec3::Zero(), e1 = Vec3::Zero();
    if (r != Region::Zero) e0 = p - positions.row(tree0.nearest(p)).transpose();
    if (r != Region::One) e1 = p - positions.row(tree1.nearest(p)).transpose();
    const double d0 = e0.norm(), d1 = e1.norm();
    if (d0 + d1 == 0.0) {
      conflict = std::min(conflict, static_cast<Index>(i));
      continue;
    }
    if (r == Region::Zero) continue;  // lambda 0, gradient 0
    if (r == Region::One) {
      fields.lambda[i] = 1.0;
      continue;
    }
    const double sum = d0 + d1;
    fields.lambda[i] = d0 / sum;
    // grad lambda = (d1 grad d0 - d0 grad d1) / (d0 + d1)^2, grad d = offset / d (units 1 / model unit);
    // left at zero where a distance vanishes (direction undefined; lambda is at an end there).
    if (d0 > 0.0 && d1 > 0.0) {
      fields.grad_lambda.row(i) = ((d1 / d0) * e0 - (d0 / d1) * e1).transpose() / (sum * sum);
    }
  }
  if (conflict != std::numeric_limits<Index>::max()) {
    throw Error(ErrorCode::Conflict, "regions",
                "row " + std::to_string(conflict) +
                    " lies in both F0 and F1 (d0 + d1 == 0): the regions overlap");
  }
  return fields;
}

DeformResult apply_step(const DeformationFields& fields, const DeformParams& params, Points& positions,
                        Points& normals, Points* tangent_u, Points* tangent_v, int threads) {
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
  require_rows(fields.lambda.size(), "fields.lambda");
  require_rows(fields.grad_lambda.rows(), "fields.grad_lambda");
  require_rows(normals.rows(), "normals");
  const bool has_u = tangent_u && tangent_u->rows() > 0;
  const bool has_v = tangent_v && tangent_v->rows() > 0;
  if (has_u) require_rows(tangent_u->rows(), "tangent_u");
  if (has_v) require_rows(tangent_v->rows(), "tangent_v");

  // One pass over the deformable rows: check the fields, collect the moved rows (s > 0) and, when
  // no centre is given, F1's centroid (shifted mean relative to the first F1 row, for precision far
  // from the origin). The model arrays themselves are not scanned for non-finite values here: the
  // step is memory-bound and a second full read of positions/normals/gradients would double its
  // cost; they were validated where they entered (compute_fields, the model), and a non-finite F1
  // position still shows up as a non-finite centroid below.
  DeformResult result;
  result.moved.reserve(fields.deformable.size());
  Vec3 f1_ref = Vec3::Zero(), f1_sum = Vec3::Zero();
  std::size_t f1_count = 0;
  Index prev = -1;
  const bool need_centroid = !params.center;
  const double* Pc = positions.data();
  const Blend blend = params.blend;
  for (const Index i : fields.deformable) {
    if (i <= prev || i >= n) {
      throw Error(ErrorCode::InvalidArgument, "fields.deformable",
                  "row " + std::to_string(i) + " is out of range or not ascending");
    }
    prev = i;
    const Region region = fields.regions[static_cast<std::size_t>(i)];
    const double l = fields.lambda[i];
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
    if (blend_value(blend, l) > 0.0) result.moved.push_back(i);
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
  const Vec3 c = result.center;
  const Vec3 t = params.translation;
  const double alpha = params.angle;
  const bool rotate = alpha != 0.0;
  const Vec3 a = rotate ? Vec3(params.axis.normalized()) : Vec3::UnitZ();
  const Index* moved = result.moved.data();
  const Eigen::Index n_moved = static_cast<Eigen::Index>(result.moved.size());
  double* P = positions.data();
  double* N = normals.data();
  double* U = has_u ? tangent_u->data() : nullptr;
  double* V = has_v ? tangent_v->data() : nullptr;
  const double* G = fields.grad_lambda.data();

  // Per moved row. J = R (I + w g^T) with g = grad s = beta'(lambda) grad lambda and
  // w = R^T dF/ds = alpha (a x (p - c)) + R^T t (R commutes with rotations about a). Hence
  //   J x = R (x + w (g . x)),  cofactor(J) n = R ((1 + g . w) n - (w . n) g),
  // the latter being J u x J v for an orthonormal tangent frame (u, v) of n.
  // One sin/cos pair per blend row; F1 rows (s = 1) share the step's rotation r1.
  // Plain scalar 3-vectors (V3) here: Eigen's 2-wide packets on 3-vectors cost more shuffles than
  // they save in this loop.
  const V3 cv = V3::of(c), tv = V3::of(t), av = V3::of(a);
  const double sin_full = std::sin(alpha), cos_full = std::cos(alpha);
  const R3 r1 = R3::rotation(av, cos_full, sin_full);  // the full step's rotation
  const V3 axt = cross(av, tv);                         // a x t
  const double adt = dot(av, tv);                       // a . t
  auto step_row = [&](Index i) {
    const bool one = fields.regions[static_cast<std::size_t>(i)] == Region::One;
    const double l = fields.lambda[i];
    const double s = one ? 1.0 : blend_value(blend, l);
    const std::ptrdiff_t o = 3 * static_cast<std::ptrdiff_t>(i);
    const V3 p = V3::load(P + o);
    V3 g{0.0, 0.0, 0.0};
    if (!one) g = blend_derivative(blend, l) * V3::load(G + o);
    const bool flat = g.x == 0.0 && g.y == 0.0 && g.z == 0.0;  // J = R
    if (!rotate) {
      // Translation only: R = I, w = t.
      (p + s * tv).store(P + o);
      if (flat) return;  // J = I: normals and tangents unchanged
      const V3 nrm = V3::load(N + o);
      const V3 m = (1.0 + dot(g, tv)) * nrm - dot(tv, nrm) * g;
      const double len2 = dot(m, m);
      if (len2 > 0.0) ((dot(m, nrm) < 0.0 ? -1.0 : 1.0) / std::sqrt(len2) * m).store(N + o);
      if (U) {
        const V3 u = V3::load(U + o);
        (u + dot(g, u) * tv).store(U + o);
      }
      if (V) {
        const V3 v = V3::load(V + o);
        (v + dot(g, v) * tv).store(V + o);
      }
      return;
    }
    const V3 rel = p - cv;
    const V3 nrm = V3::load(N + o);
    if (one) {
      // F1: the one rotation of the step, a rigid motion (lengths preserved, no renormalisation).
      (r1 * rel + cv + tv).store(P + o);
      (r1 * nrm).store(N + o);
      if (U) (r1 * V3::load(U + o)).store(U + o);
      if (V) (r1 * V3::load(V + o)).store(V + o);
      return;
    }
    const double th = s * alpha;
    const double sn = std::sin(th), cs = std::cos(th);  // one sincos call (GCC fuses the pair)
    const R3 rot = R3::rotation(av, cs, sn);
    (rot * rel + cv + s * tv).store(P + o);
    if (flat) {
      const V3 rn = rot * nrm;
      ((1.0 / std::sqrt(dot(rn, rn))) * rn).store(N + o);
      if (U) (rot * V3::load(U + o)).store(U + o);
      if (V) (rot * V3::load(V + o)).store(V + o);
      return;
    }
    // R^T t = cos t - sin (a x t) + (1 - cos)(a . t) a
    const V3 w = alpha * cross(av, rel) + (cs * tv - sn * axt + ((1.0 - cs) * adt) * av);
    V3 m = (1.0 + dot(g, w)) * nrm - dot(w, nrm) * g;
    double len2 = dot(m, m);
    if (!(len2 > 0.0)) {
      m = nrm;
      len2 = dot(m, m);
    }
    // |R m| = |m|: normalise with m's length; the sign makes the normal agree with R n.
    ((dot(m, nrm) < 0.0 ? -1.0 : 1.0) / std::sqrt(len2) * (rot * m)).store(N + o);
    if (U) {
      const V3 u = V3::load(U + o);
      (rot * (u + dot(g, u) * w)).store(U + o);
    }
    if (V) {
      const V3 v = V3::load(V + o);
      (rot * (v + dot(g, v) * w)).store(V + o);
    }
  };

  if (nthreads == 1 || n_moved < 4096) {
    for (Eigen::Index k = 0; k < n_moved; ++k) step_row(moved[k]);
  } else {
#pragma omp parallel for schedule(static) num_threads(nthreads)
    for (Eigen::Index k = 0; k < n_moved; ++k) step_row(moved[k]);
  }
  return result;
}

}  // namespace surfeledit
