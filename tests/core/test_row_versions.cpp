// Row versions in 4 bytes a row (row_versions.hpp, issue 14 memory): exact while a session stays within
// 2^32 versions of the floor; past it the floor rises, older rows read as the floor, and the session answers
// a question about changes since a version below the floor with a full update.
#include <gtest/gtest.h>

#include <cstring>
#include <set>

#include "session_fixture.hpp"
#include "surfeledit/core/row_versions.hpp"
#include "surfeledit/core/snapshot_io.hpp"

namespace surfeledit {
namespace {

constexpr std::uint64_t kSpan = RowVersions::kSpan;

TEST(RowVersions, ExactWithinTheSpanThenTheFloorRises) {
  RowVersions v;
  v.assign(3, 5);
  v.set(1, 9);
  v.set(2, 5 + kSpan);  // the largest offset: no rise
  EXPECT_EQ(v.floor(), 5u);
  EXPECT_EQ(v[0], 5u);
  EXPECT_EQ(v[1], 9u);
  EXPECT_EQ(v[2], 5 + kSpan);
  EXPECT_EQ(v.memory_bytes(), 3 * sizeof(std::uint32_t));
  const std::uint64_t far = 6 + kSpan;  // one past: the floor rises to far - kSpan / 2
  v.set(0, far);
  EXPECT_EQ(v.floor(), far - kSpan / 2);
  EXPECT_EQ(v[0], far);
  EXPECT_EQ(v[1], v.floor());  // 9 is below the new floor: read as the floor
  EXPECT_EQ(v[2], 5 + kSpan);  // above it: exact
  v.set(2, 7);                 // an old version put back: the floor
  EXPECT_EQ(v[2], v.floor());
  v.push_back(far + 3);
  v.resize(6, far + 4);
  EXPECT_EQ(v.size(), 6u);
  EXPECT_EQ(v[3], far + 3);
  EXPECT_EQ(v[5], far + 4);
  v.compact({true, false, true, false, true, true});
  ASSERT_EQ(v.size(), 4u);
  EXPECT_EQ(v[0], far);
  EXPECT_EQ(v[1], v.floor());
  EXPECT_EQ(v[2], far + 4);
  // A far jump on a resize: every row, the new ones included, against the new floor.
  v.resize(5, far + 3 * kSpan);
  EXPECT_EQ(v.floor(), far + 3 * kSpan - kSpan / 2);
  for (std::size_t r = 0; r < 4; ++r) EXPECT_EQ(v[r], v.floor());
  EXPECT_EQ(v[4], far + 3 * kSpan);
}

// The 8 little-endian bytes of `v` at their only place in `bytes` followed by those of `then` (the
// snapshot's version and model version), replaced by `by`'s.
void patch_version(std::string& bytes, std::uint64_t v, std::uint64_t then, std::uint64_t by) {
  char pattern[16];
  std::memcpy(pattern, &v, 8);
  std::memcpy(pattern + 8, &then, 8);
  const std::string p(pattern, 16);
  const std::size_t at = bytes.find(p);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes.find(p, at + 1), std::string::npos) << "the version's bytes are not unique";
  std::memcpy(&bytes[at], &by, 8);
}

// A session whose version is past 2^32 (a snapshot of one with its version moved on): a step's moved rows
// are exactly the changes since the version before it, and a client that last saw a version below the
// floor is told to take everything.
TEST(RowVersions, ASessionPastTheSpanAnswersBelowTheFloorWithAFullUpdate) {
  SessionFixture f;
  f.session.configure({{"algorithm", std::string("none")}});
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  const std::uint64_t loaded = f.session.changes_since(0).full ? 1 : 0;  // (the load is a full update)
  EXPECT_EQ(loaded, 1u);
  SnapshotWriter w;
  f.session.save(w);
  std::string bytes = w.bytes();
  const std::uint64_t far = f.session.version() + 3 * kSpan;
  std::uint64_t model_version = 0;
  for (std::uint64_t v = 0; v <= f.session.version(); ++v)
    if (!f.session.changes_since(v).full) {
      model_version = v;  // the first version not answered in full is the model's
      break;
    }
  patch_version(bytes, f.session.version(), model_version, far);
  EditSession s{"far"};
  SnapshotReader r(bytes);
  s.restore(r);
  ASSERT_EQ(s.version(), far);
  DeformParams p;
  p.translation = Vec3(0.01, 0, 0);
  const StepResult step = s.deform(p);
  ASSERT_FALSE(step.moved.empty());
  std::set<SurfelId> moved;
  for (Index row : step.moved) moved.insert(s.model().id_of(row));
  // Exact: the rows the step moved, nothing else.
  const Changes recent = s.changes_since(far);
  EXPECT_FALSE(recent.full);
  EXPECT_EQ(std::set<SurfelId>(recent.changed.begin(), recent.changed.end()), moved);
  // Below the floor (the rows the step did not move read as the floor): everything.
  const Changes old = s.changes_since(far - kSpan);
  EXPECT_TRUE(old.full);
  EXPECT_EQ(old.changed.size(), static_cast<std::size_t>(s.model().size()));
}

}  // namespace
}  // namespace surfeledit
