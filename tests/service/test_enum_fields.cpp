// Enum-valued request fields travel as long (PROTOCOL.md, "Reply guarantee"): any number decodes, and
// values outside their enum get InvalidArgument naming the field.
#include <gtest/gtest.h>

#include <climits>
#include <string>

#include "handler_fixture.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

namespace {

TEST_F(HandlerTest, OpNumbersOutsideTheEnumAreRefusedNamingTheOp) {
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  for (const std::int32_t op : {static_cast<std::int32_t>(kOpCount), 99, -1, INT32_MIN, INT32_MAX}) {
    surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_INFO, next_id++);
    req.op = op;
    const auto r = handler.handle(decode(req), updates);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->status, Status::InvalidArgument) << op;
    EXPECT_EQ(r->field, "op") << op;
  }
}

TEST_F(HandlerTest, SettingKindsOutsideTheEnumAndNamelessSettingsNameTheField) {
  ASSERT_EQ(send(surfeledit_proto_OP_OPEN_SESSION)->status, Status::Ok);
  std::string name = "boundary_n", empty;
  surfeledit_proto_Setting settings[2]{};
  settings[0].name = name.data();
  settings[0].kind = surfeledit_proto_SETTING_INT;
  settings[0].number = 4;
  settings[1].name = name.data();
  settings[1].kind = 9;
  surfeledit_proto_Configure configure{};
  configure.settings._buffer = settings;
  configure.settings._length = configure.settings._maximum = 2;
  auto send_configure = [&] {
    surfeledit_proto_Request req = rb.make(surfeledit_proto_OP_CONFIGURE, next_id++);
    req.configure._buffer = &configure;
    req.configure._length = req.configure._maximum = 1;
    return handler.handle(decode(req), updates);
  };
  auto r = send_configure();
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "boundary_n");
  EXPECT_NE(r->message.find("unknown setting kind 9"), std::string::npos) << r->message;
  settings[1].kind = surfeledit_proto_SETTING_NUMBER;
  settings[1].name = empty.data();  // found by the request fuzzer: the error had no field
  r = send_configure();
  EXPECT_EQ(r->status, Status::InvalidArgument);
  EXPECT_EQ(r->field, "configure.settings[1].name");
}

}  // namespace
