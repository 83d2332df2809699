// Extended (concave) narrow phase: inside/outside against the original model with a step-stamped
// cache of the state before the step (thesis §8.4).
#include "surfeledit/core/bvh/extended.hpp"

#include <utility>

namespace surfeledit::bvh {

ExtendedNarrow::ExtendedNarrow(std::shared_ptr<const InsideOutside> original, std::vector<std::uint8_t> is_zero,
                               Index rows, double threshold)
    : original_(std::move(original)),
      is_zero_(std::move(is_zero)),
      threshold_(threshold),
      cache_(static_cast<std::size_t>(rows)),
      colliding_(static_cast<std::size_t>(rows), 0) {
  if (!original_) throw Error(ErrorCode::InvalidArgument, "original", "an inside/outside structure is required");
}

void ExtendedNarrow::begin_step(std::int64_t step, const Points& current, const Points& previous) {
  if (step <= step_) throw Error(ErrorCode::InvalidArgument, "step", "steps must increase");
  step_ = step;
  current_ = &current;
  previous_ = &previous;
}

bool ExtendedNarrow::classify(const Vec3& p, bool* nearest_is_zero) const {
  Index nearest = -1;
  double offset = 0.0;
  original_->inside(p, threshold_, &nearest, &offset);
  if (nearest_is_zero)
    *nearest_is_zero = nearest >= 0 && static_cast<std::size_t>(nearest) < is_zero_.size() && is_zero_[nearest];
  return offset < threshold_;
}

void ExtendedNarrow::operator()(Index row) {
  const std::size_t r = static_cast<std::size_t>(row);
  Cached& c = cache_[r];
  bool before;
  if (c.step == step_ - 1) {
    before = c.inside;
  } else {
    before = classify(previous_->row(row).transpose(), nullptr);
    ++evaluations_;
  }
  bool nearest_zero = false;
  const bool now = classify(current_->row(row).transpose(), &nearest_zero);
  ++evaluations_;
  if (nearest_zero && now != before) colliding_[r] ^= 1u;
  c.step = step_;
  c.inside = now;
}

IndexList ExtendedNarrow::colliding_rows() const {
  IndexList out;
  for (std::size_t r = 0; r < colliding_.size(); ++r)
    if (colliding_[r]) out.push_back(static_cast<Index>(r));
  return out;
}

void ExtendedNarrow::on_removed(const std::vector<bool>& keep) {
  std::size_t w = 0;
  for (std::size_t r = 0; r < keep.size() && r < cache_.size(); ++r) {
    if (!keep[r]) continue;
    cache_[w] = cache_[r];
    colliding_[w] = colliding_[r];
    ++w;
  }
  cache_.resize(w);
  colliding_.resize(w);
}

void ExtendedNarrow::on_inserted(const IndexList& parents) {
  for (Index p : parents) {
    const std::size_t pr = static_cast<std::size_t>(p);
    cache_.push_back(pr < cache_.size() ? cache_[pr] : Cached{});
    colliding_.push_back(pr < colliding_.size() ? colliding_[pr] : std::uint8_t{0});
  }
}

}  // namespace surfeledit::bvh
