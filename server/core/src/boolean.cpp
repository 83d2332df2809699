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

// One side: for each surfel of (p, n, r), whether it is inside the other model `other` and whether it is
// near its surface (the feature test).
void classify_side(const Points& p, const Values& r, const InsideOutside& other, const Values& other_radii,
                   const BooleanParams& params, std::vector<std::uint8_t>& inside, std::vector<std::uint8_t>& near) {
  const Index n = static_cast<Index>(p.rows());
  inside.assign(static_cast<std::size_t>(n), 0);
  near.assign(static_cast<std::size_t>(n), 0);
  const double f = params.feature_factor;
#pragma omp parallel for schedule(static) num_threads(resolve_threads(params.threads))
  for (Index i = 0; i < n; ++i) {
    const Vec3 q = p.row(i).transpose();
    Index nearest = -1;
    double offset = 0.0;
    inside[i] = other.inside(q, 0.0, &nearest, &offset) ? 1 : 0;
    double dist2 = 0.0;
    other.tree().nearest(q, &dist2);
    const double reach = f * (r[i] + other_radii[nearest]);
    near[i] = (std::abs(offset) <= f * r[i] && dist2 <= reach * reach) ? 1 : 0;
  }
}

}  // namespace

BooleanClassification classify_boolean(const Points& pa, const Points& na, const Values& ra, const Points& pb,
                                       const Points& nb, const Values& rb, BooleanOp op,
                                       const BooleanParams& params) {
  validate(params);
  KdTreeParams kp;
  kp.threads = params.threads;
  const InsideOutside in_a(pa, na, kp), in_b(pb, nb, kp);
  std::vector<std::uint8_t> a_in_b, a_near, b_in_a, b_near;
  classify_side(pa, ra, in_b, rb, params, a_in_b, a_near);
  classify_side(pb, rb, in_a, ra, params, b_in_a, b_near);
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
