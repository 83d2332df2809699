// BvhParams: defaults are valid, each bound is enforced with the field named, update names round-trip.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "surfeledit/core/bvh/params.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit::bvh {
namespace {

void expect_rejected(const std::function<void(BvhParams&)>& set, const std::string& field) {
  BvhParams p;
  set(p);
  try {
    validate(p);
    ADD_FAILURE() << "accepted bad " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), field);
  }
}

TEST(BvhParams, BoundsAreEnforcedAndNamed) {
  EXPECT_NO_THROW(validate(BvhParams{}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_rejected([](BvhParams& p) { p.max_level = -1; }, "max_level");
  expect_rejected([](BvhParams& p) { p.max_level = 65; }, "max_level");
  expect_rejected([](BvhParams& p) { p.leaf_min_surfels = 0; }, "leaf_min_surfels");
  expect_rejected([](BvhParams& p) { p.leaf_min_surfels = 5, p.leaf_max_surfels = 4; }, "leaf_max_surfels");
  expect_rejected([](BvhParams& p) { p.min_leaf_extent = -1e-6; }, "min_leaf_extent");
  expect_rejected([nan](BvhParams& p) { p.min_leaf_extent = nan; }, "min_leaf_extent");
  expect_rejected([](BvhParams& p) { p.inflation = std::numeric_limits<double>::infinity(); }, "inflation");
  expect_rejected([](BvhParams& p) { p.hybrid_f = 1.0000001; }, "hybrid_f");
  expect_rejected([nan](BvhParams& p) { p.hybrid_f = nan; }, "hybrid_f");
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
  try {
    parse_update("sideways", "tree.update");
    ADD_FAILURE() << "accepted an unknown update mode";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "tree.update");
  }
}

}  // namespace
}  // namespace surfeledit::bvh
