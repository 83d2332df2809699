// BvhParams: defaults are valid, each bound is enforced with the field named, update names round-trip.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "expect_error.hpp"
#include "surfeledit/core/bvh/params.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::bvh {
namespace {

template <class Set>
void rejected(Set&& set, const std::string& field) {
  testing_util::expect_rejected<BvhParams>(set, field);
}

TEST(BvhParams, BoundsAreEnforcedAndNamed) {
  EXPECT_NO_THROW(validate(BvhParams{}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  rejected([](auto& p) { p.max_level = -1; }, "max_level");
  rejected([](auto& p) { p.max_level = 65; }, "max_level");
  rejected([](auto& p) { p.leaf_min_surfels = 0; }, "leaf_min_surfels");
  rejected([](auto& p) { p.leaf_min_surfels = 5, p.leaf_max_surfels = 4; }, "leaf_max_surfels");
  rejected([](auto& p) { p.min_leaf_extent = -1e-6; }, "min_leaf_extent");
  rejected([nan](auto& p) { p.min_leaf_extent = nan; }, "min_leaf_extent");
  rejected([](auto& p) { p.inflation = std::numeric_limits<double>::infinity(); }, "inflation");
  rejected([](auto& p) { p.hybrid_f = 1.0000001; }, "hybrid_f");
  rejected([nan](auto& p) { p.hybrid_f = nan; }, "hybrid_f");
  // The edges of each range are accepted.
  BvhParams edge;
  edge.max_level = 64;
  edge.leaf_min_surfels = edge.leaf_max_surfels = 1;
  edge.hybrid_f = 0.0;
  EXPECT_NO_THROW(validate(edge));
  edge.max_level = 0;
  edge.hybrid_f = 1.0;
  EXPECT_NO_THROW(validate(edge));
}

TEST(BvhParams, UpdateNamesRoundTrip) {
  for (UpdateMode m : {UpdateMode::BottomUp, UpdateMode::TopDown, UpdateMode::Hybrid})
    EXPECT_EQ(parse_update(to_string(m)), m);
  testing_util::expect_error([] { parse_update("sideways", "tree.update"); }, ErrorCode::InvalidArgument,
                             "tree.update");
}

}  // namespace
}  // namespace surfeledit::bvh
