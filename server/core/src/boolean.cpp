// Boolean operations of two surfel models: classification by the inside/outside operator, feature surfels.
#include "surfeledit/core/boolean.hpp"

#include <cmath>
#include <string>

#include "surfeledit/core/inside_outside.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

void validate(const BooleanParams& p) {
  if (!(p.feature_factor >= 0.0) || !std::isfinite(p.feature_factor))
    throw Error(ErrorCode::InvalidArgument, "feature_factor",
                "feature_factor = " + std::to_string(p.feature_factor) + ": must be a finite number >= 0");
}

namespace {

// The other model of one side: an exact and an approximate (eps = 1, at most sqrt(2) x as far) inside/outside
// operator over its surfels. A query far from the other surface (its approximate nearest surfel more than
// kDeep x the largest radius away) is classified by the approximate one (any near-nearest surfel gives the
// same side there, and exact queries deep inside are slow); a query near it by the exact one.
struct Other {
  const Points& positions;
  const Values& radii;
  InsideOutside exact, approx;
  double deep = 0.0;
  static constexpr double kDeep = 4.0;
  Other(const Points& p, const Points& n, const Values& r, int threads)
      : positions(p), radii(r), exact(p, n, params(threads, 0.0)), approx(p, n, params(threads, 1.0)),
        deep(kDeep * (r.size() > 0 ? r.maxCoeff() : 0.0)) {}
  static KdTreeParams params(int threads, double eps) {
    KdTreeParams kp;
    kp.threads = threads;
    kp.eps = eps;
    return kp;
  }
};

// One side: for each surfel of (p, r), whether it is inside the other model and whether it is near its
// surface (the feature test).
void classify_side(const Points& p, const Values& r, const Other& other, const BooleanParams& params,
                   std::vector<std::uint8_t>& inside, std::vector<std::uint8_t>& near) {
  const Index n = static_cast<Index>(p.rows());
  inside.assign(static_cast<std::size_t>(n), 0);
  near.assign(static_cast<std::size_t>(n), 0);
  const double f = params.feature_factor;
#pragma omp parallel for schedule(dynamic, 256) num_threads(resolve_threads(params.threads))
  for (Index i = 0; i < n; ++i) {
    const Vec3 q = p.row(i).transpose();
    Index nearest = -1;
    double offset = 0.0;
    bool in = other.approx.inside(q, 0.0, &nearest, &offset);
    double dist = (q - other.positions.row(nearest).transpose()).norm();
    if (dist <= other.deep) {
      in = other.exact.inside(q, 0.0, &nearest, &offset);
      dist = (q - other.positions.row(nearest).transpose()).norm();
    }
    inside[i] = in ? 1 : 0;
    const double reach = f * (r[i] + other.radii[nearest]);
    near[i] = (std::abs(offset) <= f * r[i] && dist <= reach) ? 1 : 0;
  }
}

}  // namespace

BooleanClassification classify_boolean(const Points& pa, const Points& na, const Values& ra, const Points& pb,
                                       const Points& nb, const Values& rb, BooleanOp op,
                                       const BooleanParams& params) {
  validate(params);
  if (ra.size() != pa.rows() || rb.size() != pb.rows())
    throw Error(ErrorCode::InvalidArgument, "radii", "expected one radius per surfel of each model");
  const Other a(pa, na, ra, params.threads), b(pb, nb, rb, params.threads);
  std::vector<std::uint8_t> a_in_b, a_near, b_in_a, b_near;
  classify_side(pa, ra, b, params, a_in_b, a_near);
  classify_side(pb, rb, a, params, b_in_a, b_near);
  BooleanClassification out;
  out.keep_a.resize(a_in_b.size());
  out.keep_b.resize(b_in_a.size());
  const bool a_inside = op == BooleanOp::Intersection, b_inside = op != BooleanOp::Union;
  for (std::size_t i = 0; i < a_in_b.size(); ++i) {
    out.keep_a[i] = (a_in_b[i] != 0) == a_inside;
    if (out.keep_a[i] && a_near[i]) out.features_a.push_back(static_cast<Index>(i));
  }
  for (std::size_t i = 0; i < b_in_a.size(); ++i) {
    out.keep_b[i] = (b_in_a[i] != 0) == b_inside;
    if (out.keep_b[i] && b_near[i]) out.features_b.push_back(static_cast<Index>(i));
  }
  return out;
}

}  // namespace surfeledit
