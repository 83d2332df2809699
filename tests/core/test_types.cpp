// The core's typed error: names of the codes, the message naming the field, and require_finite
// naming the first bad entry (row, column) of a row-major array.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "expect_error.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {
namespace {

TEST(Types, ErrorCodeNamesAreDistinct) {
  const ErrorCode codes[] = {ErrorCode::InvalidArgument, ErrorCode::NotFound, ErrorCode::Conflict,
                             ErrorCode::TooLarge,        ErrorCode::Io,       ErrorCode::Internal};
  std::set<std::string> names;
  for (ErrorCode c : codes) names.insert(to_string(c));
  EXPECT_EQ(names.size(), 6u);
  EXPECT_STREQ(to_string(ErrorCode::InvalidArgument), "invalid_argument");
  EXPECT_STREQ(to_string(ErrorCode::NotFound), "not_found");
  EXPECT_STREQ(to_string(ErrorCode::Io), "io");
  EXPECT_STREQ(to_string(static_cast<ErrorCode>(99)), "unknown");
}

TEST(Types, ErrorMessageNamesTheField) {
  const Error e(ErrorCode::Conflict, "regions", "zero and one overlap");
  EXPECT_EQ(e.code(), ErrorCode::Conflict);
  EXPECT_EQ(e.field(), "regions");
  EXPECT_STREQ(e.what(), "regions: zero and one overlap");
  const Error bare(ErrorCode::Internal, "", "broken");
  EXPECT_EQ(bare.field(), "");
  EXPECT_STREQ(bare.what(), "broken");
}

TEST(Types, RequireFiniteNamesFirstBadRowAndColumn) {
  Points p = Points::Zero(4, 3);
  EXPECT_NO_THROW(require_finite(p, "positions"));
  p(2, 1) = std::numeric_limits<double>::quiet_NaN();
  p(3, 0) = std::numeric_limits<double>::infinity();  // later in row-major order: not the one named
  const std::string msg = testing_util::expect_error([&] { require_finite(p, "positions"); },
                                                     ErrorCode::InvalidArgument, "positions");
  EXPECT_NE(msg.find("row 2, column 1"), std::string::npos) << msg;
  Values v = Values::Ones(5);
  v[4] = -std::numeric_limits<double>::infinity();
  const std::string msg_v = testing_util::expect_error([&] { require_finite(v, "radii"); },  // #P by 1
                                                       ErrorCode::InvalidArgument, "radii");
  EXPECT_NE(msg_v.find("row 4, column 0"), std::string::npos) << msg_v;
}

}  // namespace
}  // namespace surfeledit
