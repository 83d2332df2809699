// SurfelModel: validation, stable ids across insertion and removal, hashing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {
namespace {

SurfelArrays random_arrays(Index n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  SurfelArrays a;
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  a.radii.resize(n);
  for (Index i = 0; i < n; ++i) {
    a.positions.row(i) << u(rng), u(rng), u(rng);
    a.normals.row(i) << u(rng), u(rng), 2.0;  // never zero
    a.radii[i] = 0.01 + 0.01 * (u(rng) + 1.0);
  }
  return a;
}

TEST(SurfelModel, AssignsIdsInOrderAndNormalisesNormals) {
  const SurfelModel m = SurfelModel::from_arrays(random_arrays(50, 1));
  ASSERT_EQ(m.size(), 50);
  for (Index i = 0; i < 50; ++i) {
    EXPECT_EQ(m.ids()[i], static_cast<SurfelId>(i));
    EXPECT_EQ(m.row_of(i), i);
    EXPECT_NEAR(m.normals().row(i).norm(), 1.0, 1e-15);
  }
  EXPECT_EQ(m.row_of(50), -1);
  EXPECT_EQ(m.next_id(), 50u);
}

TEST(SurfelModel, IdsSurviveRemovalAndInsertion) {
  const SurfelArrays original = random_arrays(20, 2);
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
  const IdList added = m.insert(random_arrays(4, 3));
  EXPECT_EQ(added, (IdList{20, 21, 22, 23}));  // fresh ids, never a removed one
  EXPECT_EQ(m.size(), 21);
  EXPECT_TRUE(std::is_sorted(m.ids().begin(), m.ids().end()));
  EXPECT_EQ(m.row_of(2), 2);   // rows before the first removal keep their place
  EXPECT_EQ(m.row_of(5), 4);   // later rows shift down past removed 3
  EXPECT_EQ(m.row_of(8), 6);   // ... and past removed 7
  m.remove({20});
  EXPECT_EQ(m.insert(random_arrays(1, 4)), (IdList{24}));
}

TEST(SurfelModel, FailedChangesLeaveTheModelAsItWas) {
  SurfelModel m = SurfelModel::from_arrays(random_arrays(10, 5));
  const std::uint64_t h = m.hash();
  EXPECT_THROW(m.remove({2, 99}), Error);  // 99 unknown: nothing removed
  EXPECT_THROW(m.remove({2, 2}), Error);   // repeated id
  IdList all;
  for (SurfelId i = 0; i < 10; ++i) all.push_back(i);
  EXPECT_THROW(m.remove(all), Error);  // would empty the model
  SurfelArrays bad = random_arrays(3, 6);
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
  SurfelArrays a = random_arrays(5, 7);
  a.normals.row(2).setZero();
  expect_field(a, "normals", ErrorCode::InvalidArgument);
  a = random_arrays(5, 7);
  a.radii[4] = -1.0;
  expect_field(a, "radii", ErrorCode::InvalidArgument);
  a = random_arrays(5, 7);
  a.positions(0, 0) = std::nan("");
  expect_field(a, "positions", ErrorCode::InvalidArgument);
  a = random_arrays(5, 7);
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

}  // namespace
}  // namespace surfeledit
