// Upload and UploadTable: inline model uploads validated chunk by chunk.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "service_test_support.hpp"
#include "surfeledit/service/upload.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(Upload, AcceptsChunksInOrderAndHandsOverTheArrays) {
  Upload up(5, true, UploadLimits{3, 100});
  const ChunkArrays first = sphere_chunk(3, 0, 5), second = sphere_chunk(2, 3, 5);
  up.add_chunk(first.data(0));
  EXPECT_EQ(up.received(), 3u);
  EXPECT_FALSE(up.complete());
  up.add_chunk(second.data(3));
  ASSERT_TRUE(up.complete());
  const SurfelArrays a = up.take();
  ASSERT_EQ(a.positions.rows(), 5);
  EXPECT_DOUBLE_EQ(a.positions(4, 2), second.positions[5]);
  EXPECT_DOUBLE_EQ(a.normals(0, 0), first.normals[0]);
  EXPECT_DOUBLE_EQ(a.radii(3), 0.1);
}

TEST(Upload, RejectsAnOffsetMismatchAndKeepsWhatItHas) {
  Upload up(4, true, UploadLimits{4, 100});
  const ChunkArrays c = sphere_chunk(2, 0, 4);
  up.add_chunk(c.data(0));
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::Conflict, "load_chunk.offset");
  expect_error([&] { up.add_chunk(c.data(3)); }, ErrorCode::Conflict, "load_chunk.offset");
  EXPECT_EQ(up.received(), 2u);
}

TEST(Upload, RejectsWrongSizes) {
  Upload up(10, true, UploadLimits{8, 100});
  ChunkArrays c = sphere_chunk(2, 0, 10);
  ChunkData d = c.data(0);
  d.positions_len = 5;
  expect_error([&] { up.add_chunk(d); }, ErrorCode::InvalidArgument, "load_chunk.positions");
  d = c.data(0);
  d.normals_len = 3;
  expect_error([&] { up.add_chunk(d); }, ErrorCode::InvalidArgument, "load_chunk.normals");
  d = c.data(0);
  d.radii_len = 1;
  expect_error([&] { up.add_chunk(d); }, ErrorCode::InvalidArgument, "load_chunk.radii");
  expect_error([&] { up.add_chunk(c.data(0, false)); }, ErrorCode::InvalidArgument, "load_chunk.radii");
  EXPECT_EQ(up.received(), 0u);

  Upload no_radii(2, false, UploadLimits{8, 100});
  expect_error([&] { no_radii.add_chunk(c.data(0, true)); }, ErrorCode::InvalidArgument, "load_chunk.radii");
  no_radii.add_chunk(c.data(0, false));
  EXPECT_TRUE(no_radii.complete());
  EXPECT_EQ(no_radii.take().radii.size(), 0);
}

TEST(Upload, RejectsWhatIsTooLarge) {
  expect_error([] { Upload(101, true, UploadLimits{8, 100}); }, ErrorCode::TooLarge, "load_begin.total");
  expect_error([] { Upload(0, true, UploadLimits{8, 100}); }, ErrorCode::InvalidArgument, "load_begin.total");
  Upload up(20, true, UploadLimits{4, 100});
  const ChunkArrays big = sphere_chunk(5, 0, 20);
  expect_error([&] { up.add_chunk(big.data(0)); }, ErrorCode::TooLarge, "load_chunk.positions");
  Upload small(3, true, UploadLimits{8, 100});
  expect_error([&] { small.add_chunk(big.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.positions");
}

TEST(Upload, RejectsBadValuesNamingTheRow) {
  Upload up(3, true, UploadLimits{8, 100});
  ChunkArrays c = sphere_chunk(3);
  c.positions[4] = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.positions[1]");
  c = sphere_chunk(3);
  c.normals[6] = c.normals[7] = c.normals[8] = 0.0;
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.normals[2]");
  c = sphere_chunk(3);
  c.radii[0] = -1.0;
  expect_error([&] { up.add_chunk(c.data(0)); }, ErrorCode::InvalidArgument, "load_chunk.radii[0]");
  EXPECT_EQ(up.received(), 0u);
}

TEST(Upload, TakeRequiresACompleteUpload) {
  Upload up(3, true, UploadLimits{8, 100});
  expect_error([&] { up.take(); }, ErrorCode::Conflict, "load_begin.total");
}

TEST(UploadTable, OneUploadPerClientAndSession) {
  UploadTable t(UploadLimits{8, 100});
  t.begin("a", "s", 3, true);
  t.begin("b", "s", 4, true);
  t.begin("a", "t", 5, false);
  EXPECT_EQ(t.size(), 3u);
  EXPECT_EQ(t.find("a", "s")->total(), 3u);
  t.begin("a", "s", 6, true);  // restarts
  EXPECT_EQ(t.find("a", "s")->total(), 6u);
  expect_error([&] { t.begin("a", "s", 1000, true); }, ErrorCode::TooLarge, "load_begin.total");
  EXPECT_EQ(t.find("a", "s")->total(), 6u);  // a failed begin keeps the old upload
  t.erase_session("s");
  EXPECT_EQ(t.size(), 1u);
  EXPECT_EQ(t.find("a", "s"), nullptr);
}

TEST(UploadTable, ReservesAsChunksArriveWithinPerClientAndTotalLimits) {
  // 7 doubles per surfel with radii: 56 bytes; limits of 10 and 14 surfels' worth.
  UploadTable t(UploadLimits{8, 100, 10 * 56, 14 * 56});
  t.begin("a", "s", 40, true);
  EXPECT_EQ(t.bytes(), 0u);  // nothing reserved at LOAD_BEGIN
  const ChunkArrays c = sphere_chunk(4, 0, 40);
  t.add_chunk("a", "s", c.data(0));
  EXPECT_EQ(t.client_bytes("a"), 4u * 56);
  t.add_chunk("a", "s", sphere_chunk(4, 4, 40).data(4));  // 8 rows (doubling)
  EXPECT_EQ(t.client_bytes("a"), 8u * 56);
  expect_error([&] { t.add_chunk("a", "s", sphere_chunk(4, 8, 40).data(8)); }, ErrorCode::TooLarge, "load_chunk");
  EXPECT_EQ(t.find("a", "s")->received(), 8u);  // the refused chunk stored nothing
  t.begin("b", "s", 40, true);
  t.add_chunk("b", "s", sphere_chunk(4, 0, 40).data(0));
  EXPECT_EQ(t.bytes(), 12u * 56);
  // b is within its own limit, but the total (14) is not.
  expect_error([&] { t.add_chunk("b", "s", sphere_chunk(4, 4, 40).data(4)); }, ErrorCode::TooLarge, "load_chunk");
  t.erase_client("a");
  EXPECT_EQ(t.bytes(), 4u * 56);
  EXPECT_EQ(t.client_bytes("a"), 0u);
  t.add_chunk("b", "s", sphere_chunk(4, 4, 40).data(4));
  EXPECT_EQ(t.client_bytes("b"), 8u * 56);
}
