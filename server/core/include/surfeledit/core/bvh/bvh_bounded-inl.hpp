// Member definitions of the bounded update of Bvh<Aabb> (bvh.hpp, UpdateMode::Bounded; the argument is
// docs/algorithms.md §5 "Bounded update"). Included by src/bvh/bvh.cpp only.
//
// Why a grown box is enough: a box fit at step s bounds the balls (p_s, r_s + |t_s|) and so the balls
// (p_s, r_s). At step m > s a surfel is within sum_{k=s+1..m} |t_k| of p_s (each step's `previous` is
// the step before's position) and its radius grew by at most the steps' radius growths, so its ball
// (p_m, r_m + |t_m|) lies in the box grown by (shift_m - shift_s) + max |t_m|. Boxes may be larger than
// a fresh fit: a larger deformable box only adds candidates, which get the same narrow test as without a
// hierarchy (src/bvh/hierarchical_detector.hpp), so the colliding set does not change.
#pragma once

#include <cmath>
#include <limits>

#include "surfeledit/core/bvh/bvh.hpp"

namespace surfeledit::bvh {

namespace detail {
// `box` grown by `g` >= 0 on every side, rounded outwards: the margin adds 2^-51 of the operands'
// size, more than the rounding of the sum, so the grown box holds the exact one.
inline Aabb grown(const Aabb& box, double g) {
  Aabb out;
  for (int d = 0; d < 3; ++d) {
    out.lo[d] = box.lo[d] - (g + (std::abs(box.lo[d]) + g) * 4.5e-16);
    out.hi[d] = box.hi[d] + (g + (std::abs(box.hi[d]) + g) * 4.5e-16);
  }
  return out;
}
}  // namespace detail

template <class Box>
template <class B, class>
Aabb Bvh<Box>::bound(std::int32_t node) const {
  const std::size_t k = static_cast<std::size_t>(node);
  const Aabb& box = nodes_[k].box;
  if (stamp_[k] == step_ || box.empty()) return box;
  // shift_ only grows (rounded up in step_bounded), so shift_ - since_ is at least the shifts in between;
  // the factor covers the subtraction's rounding.
  return detail::grown(box, ((shift_ - since_[k]) + reach_) * (1.0 + 1e-12));
}

template <class Box>
template <class B, class>
Aabb Bvh<Box>::tight_reach(std::int32_t node) const {
  const double* p = positions_->data();
  const double* q0 = previous_->data();
  const double* rad = radii_->size() ? radii_->data() : nullptr;
  double lo0 = std::numeric_limits<double>::infinity(), lo1 = lo0, lo2 = lo0;
  double hi0 = -lo0, hi1 = -lo0, hi2 = -lo0;
  auto add = [&](Index row) {
    const double* x = p + 3 * static_cast<std::ptrdiff_t>(row);
    const double* y = q0 + 3 * static_cast<std::ptrdiff_t>(row);
    const double t0 = x[0] - y[0], t1 = x[1] - y[1], t2 = x[2] - y[2];
    // The ball of this step, as the detector's (radius + own displacement, with its safety factor).
    const double r = ((rad ? rad[row] : 0.0) + std::sqrt(t0 * t0 + t1 * t1 + t2 * t2)) * (1.0 + 1e-9);
    lo0 = std::min(lo0, x[0] - r);
    lo1 = std::min(lo1, x[1] - r);
    lo2 = std::min(lo2, x[2] - r);
    hi0 = std::max(hi0, x[0] + r);
    hi1 = std::max(hi1, x[1] + r);
    hi2 = std::max(hi2, x[2] + r);
  };
  const Node& nd = nodes_[static_cast<std::size_t>(node)];
  for (std::int32_t s = nd.begin; s < nd.end; ++s)
    if (order_[s] >= 0) add(order_[s]);
  if (extras_ != 0) for_each_row(node, add);
  Aabb b;
  b.lo = Vec3(lo0, lo1, lo2);
  b.hi = Vec3(hi0, hi1, hi2);
  if (nd.leaf() && params_.min_leaf_extent > 0.0 && !b.empty()) b.enforce_min_extent(params_.min_leaf_extent);
  if (!b.empty()) b.inflate(params_.inflation);
  return b;
}

template <class Box>
template <class B, class>
void Bvh<Box>::fit_all_bounded(BvhCounters& counters) {
  for (std::size_t k = nodes_.size(); k-- > 0;) {
    const std::int32_t i = static_cast<std::int32_t>(k);
    note(k);
    Node& nd = nodes_[k];
    if (nd.leaf()) {
      compact_leaf(i);
      nd.box = tight_reach(i);
    } else {
      nd.box = nodes_[nd.first_child].box;
      nd.box.expand(nodes_[nd.first_child + 1].box);
    }
    ++counters.nu;
    stamp_[k] = step_;
    since_[k] = shift_;
  }
  refit_since_build_ = true;
}

template <class Box>
template <class B, class>
BvhCounters Bvh<Box>::step_bounded(const Points& positions, const Points& previous, const Values& radii,
                                   double shift, double reach) {
  BvhCounters c;
  positions_ = &positions;
  previous_ = &previous;
  radii_ = &radii;
  ++step_;
  // Rounded up, so that later differences shift_ - since_ never fall short of the shifts in between.
  shift_ = std::nextafter(shift_ + shift, std::numeric_limits<double>::infinity());
  reach_ = reach;
  if (shift > 0.0) refit_since_build_ = true;  // the boxes no longer fit their rows as built
  if (refit_all_) {
    refit_all_ = false;
    fit_all_bounded<Aabb, void>(c);
  }
  return c;
}

template <class Box>
template <class B, class>
bool Bvh<Box>::refit_leaf(std::int32_t node, BvhCounters& counters) {
  const std::size_t k = static_cast<std::size_t>(node);
  if (stamp_[k] == step_) return false;
  note(k);
  compact_leaf(node);
  nodes_[k].box = tight_reach(node);
  stamp_[k] = step_;
  since_[k] = shift_;
  refit_since_build_ = true;
  ++counters.nu;
  return true;
}

template <class Box>
template <class B, class>
void Bvh<Box>::tighten(std::int32_t node) {
  const std::size_t k = static_cast<std::size_t>(node);
  const std::int32_t c = nodes_[k].first_child;
  Aabb u = bound(c);
  u.expand(bound(c + 1));
  const Aabb own = bound(node);
  // Both bound the balls of this step: so does their intersection (empty when no live surfel is left).
  Aabb b;
  b.lo = own.lo.cwiseMax(u.lo);
  b.hi = own.hi.cwiseMin(u.hi);
  if (b.empty()) b = Aabb{};
  note(k);
  nodes_[k].box = b;
  stamp_[k] = step_;
  since_[k] = shift_;
}

}  // namespace surfeledit::bvh
