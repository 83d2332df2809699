// SurfelModel's optional clip lines (sharp crease): kept through insertion and removal, set by id,
// validated, in hash() only when present (unclipped models hash as before) and in memory_bytes().
#include <gtest/gtest.h>

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {
namespace {

SurfelArrays grid(Index n, double z = 0.0) {
  SurfelArrays a;
  a.positions.resize(n, 3);
  a.normals = Points::Zero(n, 3);
  a.normals.col(2).setOnes();
  a.radii = Values::Constant(n, 0.1);
  for (Index i = 0; i < n; ++i) a.positions.row(i) << 0.1 * i, 0.0, z;
  return a;
}

std::string field_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.field();
  }
  return "";
}

TEST(ClipLines, AbsentUntilSetAndHashUnchangedWithout) {
  SurfelModel m = SurfelModel::from_arrays(grid(5));
  EXPECT_FALSE(m.has_clips());
  EXPECT_EQ(m.clip_dirs().rows(), 0);
  // The hash of an unclipped model is that of ids, positions, normals and radii alone (FNV-1a).
  SurfelModel same = SurfelModel::from_arrays(grid(5));
  EXPECT_EQ(m.hash(), same.hash());
  const std::uint64_t before = m.hash();
  const std::size_t bytes = m.memory_bytes();
  Points p(1, 3), d(1, 3);
  p << 0.2, 0.0, 0.0;
  d << 0.0, 2.0, 0.0;  // normalised on the way in
  m.set_clips({2}, p, d);
  ASSERT_TRUE(m.has_clips());
  EXPECT_EQ(Vec3(m.clip_dirs().row(2)), Vec3(0, 1, 0));
  EXPECT_EQ(Vec3(m.clip_points().row(2)), Vec3(0.2, 0, 0));
  EXPECT_EQ(Vec3(m.clip_dirs().row(0)), Vec3::Zero());  // the others unclipped
  EXPECT_NE(m.hash(), before);
  EXPECT_EQ(m.memory_bytes(), bytes + 2 * 5 * 3 * sizeof(double));
  // A zero direction unclips.
  m.set_clips({2}, p, Points::Zero(1, 3));
  EXPECT_EQ(Vec3(m.clip_dirs().row(2)), Vec3::Zero());
}

TEST(ClipLines, KeptThroughRemovalAndInsertion) {
  SurfelModel m = SurfelModel::from_arrays(grid(5));
  Points p(2, 3), d(2, 3);
  p << 0.1, 0, 0, 0.3, 0, 0;
  d << 1, 0, 0, 0, 1, 0;
  m.set_clips({1, 3}, p, d);
  m.remove({0, 2});
  ASSERT_EQ(m.size(), 3);
  EXPECT_EQ(Vec3(m.clip_dirs().row(m.row_of(1))), Vec3(1, 0, 0));
  EXPECT_EQ(Vec3(m.clip_dirs().row(m.row_of(3))), Vec3(0, 1, 0));
  EXPECT_EQ(Vec3(m.clip_points().row(m.row_of(3))), Vec3(0.3, 0, 0));
  // Inserted without clip lines: unclipped.
  const IdList added = m.insert(grid(2, 1.0));
  ASSERT_EQ(m.clip_dirs().rows(), 5);
  EXPECT_EQ(Vec3(m.clip_dirs().row(m.row_of(added[0]))), Vec3::Zero());
  // Inserted with clip lines into a model that has none: the model's surfels become unclipped.
  SurfelModel plain = SurfelModel::from_arrays(grid(3));
  SurfelArrays clipped = grid(1, 2.0);
  clipped.clip_points = Points::Zero(1, 3);
  clipped.clip_dirs = Points::Zero(1, 3);
  clipped.clip_dirs(0, 0) = 3.0;
  const IdList one = plain.insert(clipped);
  ASSERT_TRUE(plain.has_clips());
  EXPECT_EQ(Vec3(plain.clip_dirs().row(plain.row_of(one[0]))), Vec3(1, 0, 0));
  EXPECT_EQ(Vec3(plain.clip_dirs().row(0)), Vec3::Zero());
}

TEST(ClipLines, Validated) {
  SurfelModel m = SurfelModel::from_arrays(grid(3));
  EXPECT_EQ(field_of([&] { m.set_clips({0}, Points::Zero(2, 3), Points::Zero(1, 3)); }), "clip_points");
  EXPECT_EQ(field_of([&] { m.set_clips({7}, Points::Zero(1, 3), Points::Zero(1, 3)); }), "ids");
  Points nan = Points::Zero(1, 3);
  nan(0, 1) = std::nan("");
  EXPECT_EQ(field_of([&] { m.set_clips({0}, Points::Zero(1, 3), nan); }), "clip_dirs");
  EXPECT_FALSE(m.has_clips());  // nothing changed
  SurfelArrays a = grid(3);
  a.clip_points = Points::Zero(3, 3);  // without clip_dirs
  EXPECT_EQ(field_of([&] { SurfelModel::from_arrays(a); }), "clip_dirs");
  a.clip_dirs = Points::Zero(2, 3);
  EXPECT_EQ(field_of([&] { SurfelModel::from_arrays(a); }), "clip_dirs");
}

}  // namespace
}  // namespace surfeledit
