// One check for "this call throws the core's typed Error with this code, naming this field", shared by
// the tests of validators, parsers and loaders.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "surfeledit/core/types.hpp"

namespace surfeledit::testing_util {

// Calls `call()`; records a failure unless it throws Error with `code` and field `field`. Returns the
// error's message (what()) for further checks, empty when nothing matching was thrown.
template <class Call>
std::string expect_error(Call&& call, ErrorCode code, const std::string& field) {
  try {
    call();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(e.field(), field) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error naming " << field;
  return {};
}

// Default parameters changed by `set` must be rejected by validate() (found by argument-dependent lookup
// in the namespace of Params) with InvalidArgument naming `field`.
template <class Params, class Set>
void expect_rejected(Set&& set, const std::string& field) {
  Params params;
  set(params);
  expect_error([&] { validate(params); }, ErrorCode::InvalidArgument, field);
}

}  // namespace surfeledit::testing_util
