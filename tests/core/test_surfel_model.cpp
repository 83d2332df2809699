// SurfelModel: validation, stable ids across insertion and removal, hashing, clip lines.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "random_data.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {
namespace {


TEST(SurfelModel, AssignsIdsInOrderAndNormalisesNormals) {
  const SurfelModel m = SurfelModel::from_arrays(test::random_arrays(50, 1));
  ASSERT_EQ(m.size(), 50);
  for (Index i = 0; i < 50; ++i) {
    EXPECT_EQ(m.id_of(i), static_cast<SurfelId>(i));
    EXPECT_EQ(m.row_of(i), i);
    EXPECT_NEAR(m.normals().row(i).norm(), 1.0, 1e-15);
  }
  EXPECT_EQ(m.row_of(50), -1);
  EXPECT_EQ(m.next_id(), 50u);
}

TEST(SurfelModel, IdsSurviveRemovalAndInsertion) {
  const SurfelArrays original = test::random_arrays(20, 2);
  SurfelModel m = SurfelModel::from_arrays(original);
  m.remove({3, 7, 19});
  ASSERT_EQ(m.size(), 17);
  EXPECT_EQ(m.row_of(3), -1);
  EXPECT_EQ(m.row_of(19), -1);
  // Every remaining id still addresses its original attributes.
  for (SurfelId id : m.ids()) {
    const Index r = m.row_of(id);
    ASSERT_GE(r, 0);
    EXPECT_EQ(m.positions().row(r), original.positions.row(static_cast<Index>(id)));
    EXPECT_EQ(m.radii()[r], original.radii[static_cast<Index>(id)]);
  }
  const IdList added = m.insert(test::random_arrays(4, 3));
  EXPECT_EQ(added, (IdList{20, 21, 22, 23}));  // fresh ids, never a removed one
  EXPECT_EQ(m.size(), 21);
  const IdList ids = m.ids();
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  EXPECT_EQ(m.row_of(2), 2);   // rows before the first removal keep their place
  EXPECT_EQ(m.row_of(5), 4);   // later rows shift down past removed 3
  EXPECT_EQ(m.row_of(8), 6);   // ... and past removed 7
  m.remove({20});
  EXPECT_EQ(m.insert(test::random_arrays(1, 4)), (IdList{24}));
}

TEST(SurfelModel, FailedChangesLeaveTheModelAsItWas) {
  SurfelModel m = SurfelModel::from_arrays(test::random_arrays(10, 5));
  const std::uint64_t h = m.hash();
  EXPECT_THROW(m.remove({2, 99}), Error);  // 99 unknown: nothing removed
  EXPECT_THROW(m.remove({2, 2}), Error);   // repeated id
  IdList all;
  for (SurfelId i = 0; i < 10; ++i) all.push_back(i);
  EXPECT_THROW(m.remove(all), Error);  // would empty the model
  SurfelArrays bad = test::random_arrays(3, 6);
  bad.positions(1, 2) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(m.insert(bad), Error);
  EXPECT_EQ(m.hash(), h);
  EXPECT_EQ(m.size(), 10);
}

TEST(SurfelModel, ValidationNamesFieldAndRow) {
  auto expect_field = [](SurfelArrays a, const char* field, ErrorCode code) {
    try {
      SurfelModel::from_arrays(std::move(a));
      ADD_FAILURE() << "accepted bad " << field;
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), field) << e.what();
      EXPECT_EQ(e.code(), code) << e.what();
    }
  };
  SurfelArrays a = test::random_arrays(5, 7);
  a.normals.row(2).setZero();
  expect_field(a, "normals", ErrorCode::InvalidArgument);
  a = test::random_arrays(5, 7);
  a.radii[4] = -1.0;
  expect_field(a, "radii", ErrorCode::InvalidArgument);
  a = test::random_arrays(5, 7);
  a.positions(0, 0) = std::nan("");
  expect_field(a, "positions", ErrorCode::InvalidArgument);
  a = test::random_arrays(5, 7);
  a.normals.conservativeResize(4, 3);
  expect_field(a, "normals", ErrorCode::InvalidArgument);
  expect_field(SurfelArrays{}, "positions", ErrorCode::InvalidArgument);
}

TEST(SurfelModel, EstimatedRadiiFollowSpacing) {
  // A regular grid with spacing h: the 6 nearest neighbours of an interior point are at
  // distances h (4 of them) and h*sqrt(2) (2 of them).
  const double h = 0.1;
  SurfelArrays a;
  a.positions.resize(400, 3);
  a.normals = Points::Zero(400, 3);
  a.normals.col(2).setOnes();
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) a.positions.row(i * 20 + j) << i * h, j * h, 0.0;
  const SurfelModel m = SurfelModel::from_arrays(a);
  const double expected = h * (4.0 + 2.0 * std::sqrt(2.0)) / 6.0;
  EXPECT_NEAR(m.radii()[10 * 20 + 10], expected, 1e-12);
}

// Clip lines (sharp crease): kept through insertion and removal, set by id, validated, in hash() only
// when present (unclipped models hash as before) and in memory_bytes().
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
