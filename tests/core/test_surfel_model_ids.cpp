// SurfelModel's id maps (issue 14, memory): no id list while the ids are the rows, rank bits over the id
// space after a removal. Checked against an independent id -> row map kept by the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <random>

#include "random_data.hpp"
#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {
namespace {


// Every id below next_id() against `rows` (id -> row, the test's own map), and id_of / ids() for every row.
void expect_maps(const SurfelModel& m, const std::map<SurfelId, Index>& rows) {
  ASSERT_EQ(static_cast<std::size_t>(m.size()), rows.size());
  for (SurfelId id = 0; id < m.next_id() + 3; ++id) {
    const auto it = rows.find(id);
    EXPECT_EQ(m.row_of(id), it == rows.end() ? -1 : it->second) << "id " << id;
  }
  const IdList ids = m.ids();
  ASSERT_EQ(ids.size(), rows.size());
  for (const auto& [id, row] : rows) {
    EXPECT_EQ(m.id_of(row), id);
    EXPECT_EQ(ids[static_cast<std::size_t>(row)], id);
  }
}

TEST(SurfelModelIds, RandomRemovalsAndInsertionsAgreeWithAPlainMap) {
  std::mt19937_64 rng(7);
  SurfelModel m = SurfelModel::from_arrays(test::random_arrays(300, 1));
  std::vector<SurfelId> order;  // the test's row -> id
  for (SurfelId id = 0; id < 300; ++id) order.push_back(id);
  for (int round = 0; round < 30; ++round) {
    if (round % 3 == 2) {
      const IdList added = m.insert(test::random_arrays(1 + static_cast<Index>(rng() % 40), 100 + static_cast<std::uint64_t>(round)));
      order.insert(order.end(), added.begin(), added.end());
    } else {
      IdList gone;
      for (SurfelId id : order)
        if (rng() % 9 == 0) gone.push_back(id);
      if (gone.empty() || gone.size() == order.size()) continue;
      m.remove(gone);
      std::vector<SurfelId> kept;
      std::set_difference(order.begin(), order.end(), gone.begin(), gone.end(), std::back_inserter(kept));
      order = kept;
    }
    std::map<SurfelId, Index> rows;
    for (std::size_t r = 0; r < order.size(); ++r) rows[order[r]] = static_cast<Index>(r);
    expect_maps(m, rows);
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(SurfelModelIds, NoIdListWhileTheIdsAreTheRows) {
  SurfelModel m = SurfelModel::from_arrays(test::random_arrays(1000, 2));
  const std::size_t arrays_only = 1000 * 7 * sizeof(double);  // positions, normals (3 each), radii
  EXPECT_EQ(m.memory_bytes(), arrays_only);
  m.insert(test::random_arrays(24, 3));  // insertions continue the identity
  EXPECT_EQ(m.memory_bytes(), 1024 * 7 * sizeof(double));
  std::map<SurfelId, Index> rows;
  for (Index r = 0; r < 1024; ++r) rows[static_cast<SurfelId>(r)] = r;
  expect_maps(m, rows);
  // The first removal spells the ids out: 8 bytes per row and 12 per 64 ids of rank bits.
  m.remove({5});
  EXPECT_EQ(m.memory_bytes(), 1023 * 7 * sizeof(double) + 1023 * sizeof(SurfelId) + 16 * 12);
  rows.clear();
  for (Index r = 0; r < 1023; ++r) rows[static_cast<SurfelId>(r < 5 ? r : r + 1)] = r;
  expect_maps(m, rows);
}

TEST(SurfelModelIds, TheHashAndPartsDoNotDependOnTheRepresentation) {
  const SurfelModel identity = SurfelModel::from_arrays(test::random_arrays(200, 4));
  // The same model through from_parts with the ids spelled out: the identity again, the same hash.
  const SurfelModel parts = SurfelModel::from_parts(identity.arrays(), identity.ids(), identity.next_id());
  EXPECT_EQ(parts.hash(), identity.hash());
  EXPECT_EQ(parts.memory_bytes(), identity.memory_bytes());
  // Ids 0..199 with next id 201 (id 200 removed): spelled out, and hashed the same as the identity.
  const SurfelModel spelled = SurfelModel::from_parts(identity.arrays(), identity.ids(), 201);
  EXPECT_EQ(spelled.hash(), identity.hash());
  EXPECT_GT(spelled.memory_bytes(), identity.memory_bytes());
  EXPECT_EQ(spelled.row_of(200), -1);
  EXPECT_EQ(spelled.row_of(199), 199);
  // An empty model with a next id is no snapshot a session writes.
  EXPECT_THROW(SurfelModel::from_parts(SurfelArrays{}, {}, 5), Error);
}

}  // namespace
}  // namespace surfeledit
