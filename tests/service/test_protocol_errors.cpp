// The core's errors in the protocol's terms (protocol_errors.hpp).
#include <gtest/gtest.h>

#include "service_test_support.hpp"
#include "surfeledit/service/protocol_errors.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(ProtocolErrors, StatusNumbersEqualErrorCodes) {
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::InvalidArgument)), surfeledit_proto_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::NotFound)), surfeledit_proto_STATUS_NOT_FOUND);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Conflict)), surfeledit_proto_STATUS_CONFLICT);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::TooLarge)), surfeledit_proto_STATUS_TOO_LARGE);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Io)), surfeledit_proto_STATUS_IO);
  EXPECT_EQ(static_cast<int>(status_of(ErrorCode::Internal)), surfeledit_proto_STATUS_INTERNAL);
}

TEST(ProtocolErrors, PrefixedErrorsKeepCodeAndMessage) {
  try {
    rethrow_prefixed(Error(ErrorCode::NotFound, "ids", "id 7 is unknown"), "set_regions");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::NotFound);
    EXPECT_EQ(e.field(), "set_regions.ids");
    EXPECT_EQ(message_of(e), "id 7 is unknown");
  }
  try {
    rethrow_prefixed(Error(ErrorCode::Conflict, "deform.axis", "x"), "deform");
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "deform.axis");
  }
}
