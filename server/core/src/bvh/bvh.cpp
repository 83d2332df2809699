// The one place Bvh<Box> is compiled: explicit instantiations for the three box kinds (bvh.hpp
// declares them `extern template`), the Aabb-only members of deforming trees and the step journal.
#include "surfeledit/core/bvh/bvh-inl.hpp"
#include "surfeledit/core/bvh/bvh_bounded-inl.hpp"
#include "surfeledit/core/bvh/bvh_journal-inl.hpp"

namespace surfeledit::bvh {

template class Bvh<Aabb>;
template class Bvh<Obb>;
template class Bvh<Sphere>;
template BvhCounters Bvh<Aabb>::refit<Aabb, void>(const Points&, const Values&);
template void Bvh<Aabb>::refit_touched<Aabb, void>(std::int32_t, BvhCounters&);
template void Bvh<Aabb>::touch_all<Aabb, void>(BvhCounters&);
template BvhCounters Bvh<Aabb>::step_bounded<Aabb, void>(const Points&, const Points&, const Values&, double, double);
template bool Bvh<Aabb>::refit_leaf<Aabb, void>(std::int32_t, BvhCounters&);
template void Bvh<Aabb>::tighten<Aabb, void>(std::int32_t);
template Aabb Bvh<Aabb>::bound<Aabb, void>(std::int32_t) const;

}  // namespace surfeledit::bvh
