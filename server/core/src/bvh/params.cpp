// Validation of the BVH parameters.
#include "surfeledit/core/bvh/params.hpp"

#include <cmath>

#include "surfeledit/core/types.hpp"

namespace surfeledit::bvh {

namespace {
[[noreturn]] void bad(const char* field, const std::string& what) {
  throw Error(ErrorCode::InvalidArgument, field, std::string(field) + " " + what);
}
}  // namespace

void validate(const BvhParams& p) {
  if (p.max_level < 0 || p.max_level > 64) bad("max_level", "must be in 0..64, got " + std::to_string(p.max_level));
  if (p.leaf_min_surfels < 1) bad("leaf_min_surfels", "must be >= 1, got " + std::to_string(p.leaf_min_surfels));
  if (p.leaf_max_surfels < p.leaf_min_surfels)
    bad("leaf_max_surfels", "must be >= leaf_min_surfels (" + std::to_string(p.leaf_min_surfels) + "), got " +
                                std::to_string(p.leaf_max_surfels));
  if (!std::isfinite(p.min_leaf_extent) || p.min_leaf_extent < 0.0)
    bad("min_leaf_extent", "must be finite and >= 0, got " + std::to_string(p.min_leaf_extent));
  if (!std::isfinite(p.inflation) || p.inflation < 0.0)
    bad("inflation", "must be finite and >= 0, got " + std::to_string(p.inflation));
  if (!(p.hybrid_f >= 0.0 && p.hybrid_f <= 1.0)) bad("hybrid_f", "must be in [0, 1], got " + std::to_string(p.hybrid_f));
}

}  // namespace surfeledit::bvh
