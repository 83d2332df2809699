// Update events prepared for publishing and cut into samples.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "service_test_support.hpp"
#include "surfeledit/service/convert.hpp"
#include "surfeledit/service/update.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(Update, PreparedUpdatesCopyTheRowsAndChunkIntoSlices) {
  const ChunkArrays c = sphere_chunk(5);
  SurfelArrays a;
  a.positions = Eigen::Map<const Points>(c.positions.data(), 5, 3);
  a.normals = Eigen::Map<const Points>(c.normals.data(), 5, 3);
  a.radii = Eigen::Map<const Values>(c.radii.data(), 5);
  const SurfelModel model = SurfelModel::from_arrays(a);

  UpdateEvent all;
  all.session = "s";
  all.version = 1;
  all.cause = "load";
  all.full = true;
  all.all_rows = true;
  all.removed = {99};
  const PreparedUpdate full = prepare_update(all, &model);
  ASSERT_EQ(full.surfels(), 5u);
  EXPECT_EQ(full.ids, model.ids());
  EXPECT_DOUBLE_EQ(full.positions[3 * 4 + 2], model.positions()(4, 2));
  EXPECT_DOUBLE_EQ(full.normals[3 * 2 + 1], model.normals()(2, 1));
  EXPECT_DOUBLE_EQ(full.radii[3], model.radii()(3));
  ASSERT_EQ(update_parts(full, 2), 3u);
  const UpdateChunk last = update_chunk(full, 2, 2);
  EXPECT_EQ(last.part, 2u);
  EXPECT_EQ(last.parts, 3u);
  EXPECT_EQ(last.begin, 4u);
  EXPECT_EQ(last.count, 1u);
  EXPECT_THROW(update_chunk(full, 3, 2), std::out_of_range);

  // The sample view: slices of the prepared arrays; removed / collision state in part 0 only.
  PreparedUpdate with_collision = full;
  with_collision.detected = true;
  with_collision.colliding = {1, 3};
  const UpdateView v2(update_chunk(with_collision, 2, 2));
  ASSERT_EQ(v2.get()->ids._length, 1u);
  EXPECT_EQ(v2.get()->ids._buffer[0], model.id_of(4));
  ASSERT_EQ(v2.get()->positions._length, 3u);
  EXPECT_DOUBLE_EQ(v2.get()->positions._buffer[2], model.positions()(4, 2));
  EXPECT_EQ(v2.get()->removed._length, 0u);
  EXPECT_FALSE(v2.get()->detected);
  EXPECT_EQ(v2.get()->colliding._length, 0u);
  const UpdateView v0(update_chunk(with_collision, 0, 2));
  EXPECT_EQ(v0.get()->part, 0u);
  EXPECT_EQ(v0.get()->parts, 3u);
  ASSERT_EQ(v0.get()->removed._length, 1u);
  EXPECT_EQ(v0.get()->removed._buffer[0], 99u);
  EXPECT_TRUE(v0.get()->detected);
  ASSERT_EQ(v0.get()->colliding._length, 2u);
  EXPECT_EQ(v0.get()->colliding._buffer[1], 3u);
  EXPECT_STREQ(v0.get()->cause, "load");
  EXPECT_FALSE(v0.get()->ids._release);

  UpdateEvent some;
  some.cause = "deform";
  some.rows = {1, 3};
  const PreparedUpdate two = prepare_update(some, &model);
  ASSERT_EQ(update_parts(two, 65536), 1u);
  EXPECT_EQ(two.ids, (std::vector<std::uint64_t>{model.id_of(1), model.id_of(3)}));
  EXPECT_EQ(two.radii.size(), 2u);
  some.rows = {7};
  EXPECT_THROW(prepare_update(some, &model), std::out_of_range);

  UpdateEvent close;
  close.cause = "close";
  const PreparedUpdate none = prepare_update(close, nullptr);
  EXPECT_EQ(update_parts(none, 2), 1u);
  EXPECT_EQ(update_chunk(none, 0, 2).count, 0u);
  const UpdateView vc(update_chunk(none, 0, 2));
  EXPECT_EQ(vc.get()->ids._length, 0u);
}
