// SimplifyParams: defaults are valid, each bound is enforced with the field named, method names round-trip.
#include <gtest/gtest.h>

#include <functional>
#include <limits>

#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {
namespace {

void expect_rejected(const std::function<void(SimplifyParams&)>& set, const std::string& field) {
  SimplifyParams p;
  set(p);
  try {
    validate(p);
    ADD_FAILURE() << "accepted bad " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), field);
  }
}

TEST(SimplifyParams, BoundsAreEnforcedAndNamed) {
  EXPECT_NO_THROW(validate(SimplifyParams{}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_rejected([](SimplifyParams& p) { p.method = static_cast<SimplifyMethod>(9); }, "simplify");
  expect_rejected([](SimplifyParams& p) { p.cluster_size = 0; }, "cluster_size");
  expect_rejected([](SimplifyParams& p) { p.max_variation = -0.01; }, "max_variation");
  expect_rejected([](SimplifyParams& p) { p.max_variation = 1.01; }, "max_variation");
  expect_rejected([nan](SimplifyParams& p) { p.max_variation = nan; }, "max_variation");
  expect_rejected([](SimplifyParams& p) { p.member_margin = -1.0; }, "member_margin");
  expect_rejected([](SimplifyParams& p) { p.member_margin = std::numeric_limits<double>::infinity(); },
                  "member_margin");
  expect_rejected([](SimplifyParams& p) { p.threads = -1; }, "threads");
  SimplifyParams edge;
  edge.cluster_size = 1;
  edge.max_variation = 0.0;
  edge.member_margin = 0.0;
  EXPECT_NO_THROW(validate(edge));
  edge.max_variation = 1.0;
  EXPECT_NO_THROW(validate(edge));
}

TEST(SimplifyParams, MethodNamesRoundTrip) {
  for (SimplifyMethod m : {SimplifyMethod::None, SimplifyMethod::RegionGrowing, SimplifyMethod::Hierarchical})
    EXPECT_EQ(parse_simplify_method(to_string(m)), m);
  try {
    parse_simplify_method("octree", "settings.simplify");
    ADD_FAILURE() << "accepted an unknown method";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), "settings.simplify");
  }
}

}  // namespace
}  // namespace surfeledit
