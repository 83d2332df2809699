// Deformation tool (docs/algorithms.md §1): blend fields from nearest-neighbour distances to F0 and F1 and
// the step's argument checks; the step itself (F(p, s) = R(a, s alpha)(p - c) + c + s t) is in
// deformation_step.cpp.
#include "surfeledit/core/deformation.hpp"

#include <omp.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>

#include "at_once.hpp"
#include "deformation_checks.hpp"
#include "surfeledit/core/kdtree.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

using deformation_checks::checked_threads;
using deformation_checks::fmt;
using deformation_checks::valid_blend;

namespace {
constexpr int kFieldLeafSize = 128;  // leaves of compute_fields' two trees (far exact nearest queries)
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
  for (std::size_t k = 0; k < deformable.size(); ++k) out[deformable[k]] = blend_row(k)[0];
  return out;
}

Points DeformationFields::grad_lambda() const {
  Points out = Points::Zero(static_cast<Eigen::Index>(regions.size()), 3);
  for (std::size_t k = 0; k < deformable.size(); ++k)
    out.row(deformable[k]) = Eigen::Map<const Eigen::RowVector3d>(blend_row(k) + 1);
  return out;
}

double DeformationFields::lambda_of(Index row) const {
  const auto it = std::lower_bound(deformable.begin(), deformable.end(), row);
  if (it == deformable.end() || *it != row) return 0.0;
  return blend_row(static_cast<std::size_t>(it - deformable.begin()))[0];
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

  // The blend rows ask for their nearest surfel of each region, often far from it; leaves of 128 with an oriented
  // box per node, in a frame turned along a tilted model's surfaces, visit a fraction of what leaves of 10 in world
  // axes do there (RESULTS §83). Exact; an upright model keeps the world axes and their bits, a turned one's ties may
  // go either way.
  KdTreeParams tp;
  tp.threads = nthreads;
  tp.leaf_size = kFieldLeafSize;
  tp.frames = true;
  tp.align = true;
  std::optional<KdTree> t0, t1;  // built at once on two threads for a large model (at_once.hpp)
  detail::at_once(
      detail::at_once_pays(nthreads, f0.size() + f1.size()),
      [&] { t0.emplace(positions, f0, tp); }, [&] { t1.emplace(positions, f1, tp); });
  const KdTree &tree0 = *t0, &tree1 = *t1;

  const Eigen::Index nd = static_cast<Eigen::Index>(fields.deformable.size());
  // Every deformable row in F1 (a rigid tool): all blend rows are kF1Blend, none is stored.
  const bool all_one = std::all_of(fields.deformable.begin(), fields.deformable.end(),
                                   [&](Index i) { return regions[static_cast<std::size_t>(i)] == Region::One; });
  fields.blend.setZero(all_one ? 0 : nd, 4);
  Index conflict = std::numeric_limits<Index>::max();
  // Every row is checked against the region it is not in (F0 rows against F1 too), so a surfel lying in both
  // (d0 + d1 == 0) is reported whatever its label. For a row of F0 or F1 that is all its distance is for, so its
  // search looks no further than distance 0 (nearest_within: the same tie winner as nearest(), found in about one
  // descent instead of a search as far away as the other region is).
  const auto check = [&](const IndexList& own, const KdTree& other) {
    const Eigen::Index n = static_cast<Eigen::Index>(own.size());
#pragma omp parallel for schedule(static) num_threads(nthreads) reduction(min : conflict)
    for (Eigen::Index q = 0; q < n; ++q) {
      const Index i = own[static_cast<std::size_t>(q)];
      const Vec3 p = positions.row(i).transpose();
      const Index j = other.nearest_within(p, 0.0);
      if (j >= 0 && (p - positions.row(j).transpose()).norm() == 0.0) conflict = std::min(conflict, i);
    }
  };
  check(f0, tree1);
  check(f1, tree0);
  if (!all_one) {
    // The blend rows' nearest F0 and F1 surfels, each region as one batch (answered along a space-filling curve,
    // each query bounded by the previous answer: the same rows as nearest(), the tie rule included).
    IndexList blend;  // positions in `deformable` of the blend rows
    for (Eigen::Index k = 0; k < nd; ++k) {
      if (regions[static_cast<std::size_t>(fields.deformable[static_cast<std::size_t>(k)])] == Region::One)
        fields.blend(k, 0) = 1.0;  // lambda 1, gradient 0
      else
        blend.push_back(static_cast<Index>(k));
    }
    const Eigen::Index nb = static_cast<Eigen::Index>(blend.size());
    Points queries(nb, 3);
    for (Eigen::Index b = 0; b < nb; ++b)
      queries.row(b) = positions.row(fields.deformable[static_cast<std::size_t>(blend[static_cast<std::size_t>(b)])]);
    const KnnResult near0 = tree0.knn(queries, 1, nthreads), near1 = tree1.knn(queries, 1, nthreads);
#pragma omp parallel for schedule(static) num_threads(nthreads) reduction(min : conflict)
    for (Eigen::Index b = 0; b < nb; ++b) {
      const Index k = blend[static_cast<std::size_t>(b)];
      const Index i = fields.deformable[static_cast<std::size_t>(k)];
      const Vec3 p = queries.row(b).transpose();
      // Offsets to the nearest F0 / F1 surfel (model units) and their real (not squared) lengths.
      const Vec3 e0 = p - positions.row(near0.indices(b, 0)).transpose();
      const Vec3 e1 = p - positions.row(near1.indices(b, 0)).transpose();
      const double d0 = e0.norm(), d1 = e1.norm();
      if (d0 + d1 == 0.0) {
        conflict = std::min(conflict, i);
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
  }
  if (conflict != std::numeric_limits<Index>::max()) {
    throw Error(ErrorCode::Conflict, "regions",
                "row " + std::to_string(conflict) +
                    " lies in both F0 and F1 (d0 + d1 == 0): the regions overlap");
  }
  return fields;
}

}  // namespace surfeledit
