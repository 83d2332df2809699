// Update events prepared for publishing and cut into samples.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <stdexcept>
#include <vector>

#include "service_test_support.hpp"
#include "surfeledit/service/sample_views.hpp"
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

// A step's moved rows come in runs of consecutive rows (copied run by run): every array of the prepared
// update equals the model's row, read one row at a time here, for runs at the start, the middle and the end,
// single rows between them, and with clip lines; a run reaching past the last row is refused.
TEST(Update, PreparedUpdateOfRowRunsEqualsTheModelRowByRow) {
  constexpr Index kRows = 40;
  const ChunkArrays c = sphere_chunk(kRows);
  SurfelArrays a;
  a.positions = Eigen::Map<const Points>(c.positions.data(), kRows, 3);
  a.normals = Eigen::Map<const Points>(c.normals.data(), kRows, 3);
  a.radii = Eigen::Map<const Values>(c.radii.data(), kRows);
  a.clip_points = a.positions;
  a.clip_dirs = Points::Zero(kRows, 3);
  for (Index r = 0; r < kRows; r += 3) a.clip_dirs.row(r) = a.normals.row((r + 1) % kRows).cross(a.normals.row(r)).normalized();
  for (const bool clips : {false, true}) {
    SurfelArrays arrays = a;
    if (!clips) {
      arrays.clip_points.resize(0, 3);
      arrays.clip_dirs.resize(0, 3);
    }
    const SurfelModel model = SurfelModel::from_arrays(arrays);
    ASSERT_EQ(model.has_clips(), clips);
    UpdateEvent e;
    e.cause = "deform";
    e.rows = {0, 1, 2, 3, 7, 9, 10, 11, 20, 25, 26, 27, 28, 29, 35, 36, 37, 38, 39};
    const PreparedUpdate p = prepare_update(e, &model);
    ASSERT_EQ(p.surfels(), e.rows.size());
    ASSERT_EQ(p.positions.size(), 3 * e.rows.size());
    ASSERT_EQ(p.normals.size(), 3 * e.rows.size());
    ASSERT_EQ(p.radii.size(), e.rows.size());
    ASSERT_EQ(p.clip_points.size(), clips ? 3 * e.rows.size() : 0u);
    ASSERT_EQ(p.clip_dirs.size(), p.clip_points.size());
    for (std::size_t k = 0; k < e.rows.size(); ++k) {
      const Index r = e.rows[k];
      EXPECT_EQ(p.ids[k], model.ids()[static_cast<std::size_t>(r)]) << k;
      EXPECT_EQ(p.radii[k], model.radii()(r)) << k;
      for (int j = 0; j < 3; ++j) {
        EXPECT_EQ(p.positions[3 * k + j], model.positions()(r, j)) << k;
        EXPECT_EQ(p.normals[3 * k + j], model.normals()(r, j)) << k;
        if (clips) {
          EXPECT_EQ(p.clip_points[3 * k + j], model.clip_points()(r, j)) << k;
          EXPECT_EQ(p.clip_dirs[3 * k + j], model.clip_dirs()(r, j)) << k;
        }
      }
    }
    e.rows = {37, 38, 39, 40};  // a run one row past the end
    EXPECT_THROW(prepare_update(e, &model), std::out_of_range);
    e.rows = {-1, 0, 1};
    EXPECT_THROW(prepare_update(e, &model), std::out_of_range);
  }
}
