// The load ops: LOAD_BEGIN, LOAD_CHUNK, LOAD_COMMIT.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "handler_fixture.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST_F(HandlerTest, CommitPublishesAFullUpdateAndBumpsTheVersion) {
  load(10);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(updates[0].cause, "load");
  EXPECT_TRUE(updates[0].full);
  EXPECT_EQ(updates[0].version, 1u);
  const SurfelModel* model = handler.model_of("s");
  ASSERT_NE(model, nullptr);
  EXPECT_EQ(model->size(), 10);
  EXPECT_EQ(update_parts(prepare_update(updates[0], model), 4), 3u);
}
