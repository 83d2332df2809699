// SimplifyParams: defaults are valid, each bound is enforced with the field named, method names round-trip.
#include <gtest/gtest.h>

#include <limits>

#include "expect_error.hpp"
#include "surfeledit/core/simplify/params.hpp"

namespace surfeledit {
namespace {

template <class Set>
void rejected(Set&& set, const std::string& field) {
  testing_util::expect_rejected<SimplifyParams>(set, field);
}

TEST(SimplifyParams, BoundsAreEnforcedAndNamed) {
  EXPECT_NO_THROW(validate(SimplifyParams{}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  rejected([](auto& p) { p.method = static_cast<SimplifyMethod>(9); }, "simplify");
  rejected([](auto& p) { p.cluster_size = 0; }, "cluster_size");
  rejected([](auto& p) { p.max_variation = -0.01; }, "max_variation");
  rejected([](auto& p) { p.max_variation = 1.01; }, "max_variation");
  rejected([nan](auto& p) { p.max_variation = nan; }, "max_variation");
  rejected([](auto& p) { p.member_margin = -1.0; }, "member_margin");
  rejected([](auto& p) { p.member_margin = std::numeric_limits<double>::infinity(); }, "member_margin");
  rejected([](auto& p) { p.threads = -1; }, "threads");
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
  testing_util::expect_error([] { parse_simplify_method("octree", "settings.simplify"); },
                             ErrorCode::InvalidArgument, "settings.simplify");
}

}  // namespace
}  // namespace surfeledit
