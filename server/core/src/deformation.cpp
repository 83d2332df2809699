// Deformation tool (§1): blend fields from nearest-neighbour distances to F0 and F1, and one
// step F(p, s) = R(a, s alpha)(p - c) + c + s t applied to positions, normals and tangent axes.
#include "surfeledit/core/deformation.hpp"

#include <omp.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {

namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string fmt(const Vec3& v) { return "(" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + ")"; }

int resolve_threads(int threads, const char* field) {
  if (threads < 0) {
    throw Error(ErrorCode::InvalidArgument, field, "thread count must be >= 0, got " + std::to_string(threads));
  }
  return threads > 0 ? threads : omp_get_max_threads();
}

bool valid_blend(Blend b) { return b == Blend::Smooth || b == Blend::Quadratic || b == Blend::Linear; }

// Rotation matrix about unit axis a by the angle whose cosine and sine are (c, s) (Rodrigues).
Mat3 rotation(const Vec3& a, double c, double s) {
  const double k = 1.0 - c;
  Mat3 r;
  r << c + k * a.x() * a.x(), k * a.x() * a.y() - s * a.z(), k * a.x() * a.z() + s * a.y(),
      k * a.y() * a.x() + s * a.z(), c + k * a.y() * a.y(), k * a.y() * a.z() - s * a.x(),
      k * a.z() * a.x() - s * a.y(), k * a.z() * a.y() + s * a.x(), c + k * a.z() * a.z();
  return r;
}

}  // namespace

Blend parse_blend(const std::string& name, const std::string& field) {
  if (name == "smooth") return Blend::Smooth;
  if (name == "quadratic") return Blend::Quadratic;
  if (name == "linear") return Blend::Linear;
  throw Error(ErrorCode::InvalidArgument, field,
              "unknown blend '" + name + "' (expected smooth, quadratic or linear)");
}

const char* to_string(Blend blend) {
  switch (blend) {
    case Blend::Smooth: return "smooth";
    case Blend::Quadratic: return "quadratic";
    case Blend::Linear: return "linear";
  }
  return "unknown";
}

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
  if (params.angle != 0.0 && !(params.axis.norm() > 0.0)) {
    throw Error(ErrorCode::InvalidArgument, "axis",
                "must be non-zero when angle != 0 (angle " + fmt(params.angle) + "), got " + fmt(params.axis));
  }
  if (params.center && !params.center->allFinite()) {
    throw Error(ErrorCode::InvalidArgument, "center", "must be finite, got " + fmt(*params.center));
  }
  if (!valid_blend(params.blend)) {
    throw Error(ErrorCode::InvalidArgument, "blend",
                "unknown blend value " + std::to_string(static_cast<int>(params.blend)));
  }
}

std::size_t DeformationFields::memory_bytes() const {
  return regions.capacity() * sizeof(Region) + static_cast<std::size_t>(lambda.size()) * sizeof(double) +
         static_cast<std::size_t>(grad_lambda.size()) * sizeof(double) + deformable.capacity() * sizeof(Index);
}

DeformationFields compute_fields(const Points& positions, const std::vector<Region>& regions, int threads) {
  const int nthreads = resolve_threads(threads, "threads");
  const Eigen::Index n = positions.rows();
  if (static_cast<Eigen::Index>(regions.size()) != n) {
    throw Error(ErrorCode::InvalidArgument, "regions",
                "has " + std::to_string(regions.size()) + " entries but positions have " + std::to_string(n) +
                    " rows");
  }
  require_finite(positions, "positions");
  IndexList f0, f1;
  DeformationFields fields;
  fields.regions = regions;
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
  validate(params);
  const int nthreads = resolve_threads(threads, "threads");
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

  // One pass over the deformable rows: check them, collect the moved ones (s > 0) and F1's centroid
  // (shifted mean relative to the first F1 row, for precision far from the origin).
  DeformResult result;
  result.moved.reserve(fields.deformable.size());
  Vec3 f1_ref = Vec3::Zero(), f1_sum = Vec3::Zero();
  std::size_t f1_count = 0;
  Index prev = -1;
  for (const Index i : fields.deformable) {
    if (i <= prev || i >= n) {
      throw Error(ErrorCode::InvalidArgument, "fields.deformable",
                  "row " + std::to_string(i) + " is out of range or not ascending");
    }
    prev = i;
    const Region region = fields.regions[static_cast<std::size_t>(i)];
    const double l = fields.lambda[i];
    if (region == Region::Zero || !(l >= 0.0 && l <= 1.0) || !fields.grad_lambda.row(i).allFinite()) {
      throw Error(ErrorCode::InvalidArgument, "fields",
                  "row " + std::to_string(i) + " has an inconsistent region, lambda " + fmt(l) + " or gradient");
    }
    if (!positions.row(i).allFinite() || !normals.row(i).allFinite() ||
        (has_u && !tangent_u->row(i).allFinite()) || (has_v && !tangent_v->row(i).allFinite())) {
      throw Error(ErrorCode::InvalidArgument, "positions",
                  "row " + std::to_string(i) + " has a non-finite position, normal or tangent");
    }
    if (region == Region::One) {
      const Vec3 p = positions.row(i).transpose();
      if (f1_count == 0) f1_ref = p;
      f1_sum += p - f1_ref;
      ++f1_count;
    }
    if (blend_value(params.blend, l) > 0.0) result.moved.push_back(i);
  }
  if (params.center) {
    result.center = *params.center;
  } else {
    if (f1_count == 0) {
      throw Error(ErrorCode::InvalidArgument, "center", "no centre given and the one region F1 is empty");
    }
    result.center = f1_ref + f1_sum / static_cast<double>(f1_count);
  }

  // ---- step constants ----
  const Vec3 c = result.center;
  const Vec3 t = params.translation;
  const double alpha = params.angle;
  const bool rotate = alpha != 0.0;
  const Vec3 a = rotate ? Vec3(params.axis.normalized()) : Vec3::UnitZ();
  const Mat3 r_full = rotate ? rotation(a, std::cos(alpha), std::sin(alpha)) : Mat3::Identity();
  const Blend blend = params.blend;
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
  auto step_row = [&](Index i) {
    const bool one = fields.regions[static_cast<std::size_t>(i)] == Region::One;
    const double l = fields.lambda[i];
    const double s = one ? 1.0 : blend_value(blend, l);
    double* pp = P + 3 * static_cast<std::ptrdiff_t>(i);
    double* np = N + 3 * static_cast<std::ptrdiff_t>(i);
    const Vec3 p(pp[0], pp[1], pp[2]);
    const Vec3 nrm(np[0], np[1], np[2]);
    if (!rotate) {
      // Translation only: R = I, w = t.
      const Vec3 q = p + s * t;
      pp[0] = q.x(); pp[1] = q.y(); pp[2] = q.z();
      if (one) return;  // g = 0: J = I, normals and tangents unchanged
      const double ds = blend_derivative(blend, l);
      const Vec3 g = ds * Vec3(G[3 * i], G[3 * i + 1], G[3 * i + 2]);
      if (g.x() == 0.0 && g.y() == 0.0 && g.z() == 0.0) return;
      Vec3 m = (1.0 + g.dot(t)) * nrm - t.dot(nrm) * g;
      if (m.dot(nrm) < 0.0) m = -m;
      const double len = m.norm();
      if (len > 0.0) {
        m /= len;
        np[0] = m.x(); np[1] = m.y(); np[2] = m.z();
      }
      if (U) {
        double* up = U + 3 * static_cast<std::ptrdiff_t>(i);
        const Vec3 u(up[0], up[1], up[2]);
        const Vec3 ju = u + t * g.dot(u);
        up[0] = ju.x(); up[1] = ju.y(); up[2] = ju.z();
      }
      if (V) {
        double* vp = V + 3 * static_cast<std::ptrdiff_t>(i);
        const Vec3 v(vp[0], vp[1], vp[2]);
        const Vec3 jv = v + t * g.dot(v);
        vp[0] = jv.x(); vp[1] = jv.y(); vp[2] = jv.z();
      }
      return;
    }
    const Vec3 rel = p - c;
    Mat3 rot;
    if (one) {
      rot = r_full;
    } else {
      const double th = s * alpha;
      rot = rotation(a, std::cos(th), std::sin(th));
    }
    const Vec3 q = rot * rel + c + s * t;
    pp[0] = q.x(); pp[1] = q.y(); pp[2] = q.z();
    Vec3 g = Vec3::Zero();
    if (!one) g = blend_derivative(blend, l) * Vec3(G[3 * i], G[3 * i + 1], G[3 * i + 2]);
    const bool flat = g.x() == 0.0 && g.y() == 0.0 && g.z() == 0.0;  // J = R
    Vec3 w = Vec3::Zero();
    Vec3 m = nrm;
    if (!flat) {
      w = alpha * a.cross(rel) + rot.transpose() * t;
      m = (1.0 + g.dot(w)) * nrm - w.dot(nrm) * g;
      if (m.dot(nrm) < 0.0) m = -m;
      if (!(m.squaredNorm() > 0.0)) m = nrm;
    }
    Vec3 nn = rot * m;
    const double len = nn.norm();
    if (len > 0.0) nn /= len;
    np[0] = nn.x(); np[1] = nn.y(); np[2] = nn.z();
    if (U) {
      double* up = U + 3 * static_cast<std::ptrdiff_t>(i);
      const Vec3 u(up[0], up[1], up[2]);
      const Vec3 ju = rot * (flat ? u : Vec3(u + w * g.dot(u)));
      up[0] = ju.x(); up[1] = ju.y(); up[2] = ju.z();
    }
    if (V) {
      double* vp = V + 3 * static_cast<std::ptrdiff_t>(i);
      const Vec3 v(vp[0], vp[1], vp[2]);
      const Vec3 jv = rot * (flat ? v : Vec3(v + w * g.dot(v)));
      vp[0] = jv.x(); vp[1] = jv.y(); vp[2] = jv.z();
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
