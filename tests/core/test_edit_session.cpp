// EditSession: versions, change tracking, lazily built structures, atomic failures.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>
#include <thread>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"
#include "expect_error.hpp"
#include "session_fixture.hpp"

namespace surfeledit {
namespace {

using Fixture = SessionFixture;

TEST(EditSession, VersionsAndChangesSince) {
  Fixture f;
  EXPECT_EQ(f.session.version(), 1u);
  Changes c = f.session.changes_since(0);
  EXPECT_TRUE(c.full);
  EXPECT_EQ(c.changed.size(), f.s.part.size());
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  EXPECT_EQ(f.session.version(), 2u);
  EXPECT_TRUE(f.session.changes_since(1).changed.empty());  // regions move nothing
  DeformParams p;
  p.translation = Vec3(0, 0, -0.1);
  f.session.deform(p);
  c = f.session.changes_since(2);
  EXPECT_FALSE(c.full);
  EXPECT_EQ(c.changed, f.one);  // exactly the moved surfels
  EXPECT_TRUE(f.session.changes_since(f.session.version()).changed.empty());
}

TEST(EditSession, SelectorsResolveOnCurrentPositions) {
  Fixture f;
  Selector sphere;
  sphere.kind = Selector::Kind::Sphere;
  sphere.center = Vec3(0, 0, 1.0);
  sphere.radius = 0.5 + 1e-9;  // the whole sphere part, nothing of the slab
  EXPECT_EQ(f.session.resolve({{}, {sphere}}, "one"), f.one);
  Selector box;
  box.kind = Selector::Kind::Box;
  box.half_extents = Vec3(1.5, 1.5, 0.15 + 1e-9);
  EXPECT_EQ(f.session.resolve({{}, {box}}, "zero"), f.zero);
  f.session.set_regions({{}, {box}}, {{}, {sphere}});
  EXPECT_TRUE(f.session.has_regions());
}

TEST(EditSession, BuildsFieldsOnlyWhenRegionsAreSet) {
  Fixture f;
  auto names = [&] {
    std::vector<std::string> n;
    for (const auto& s : f.session.report().structures) n.push_back(s.name);
    return n;
  };
  EXPECT_EQ(names(), (std::vector<std::string>{"model", "versions", "history"}));  // issue 9: the history is listed last
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  // The default settings run the Robust detector once regions are set; it keeps the merge origins.
  EXPECT_EQ(names(), (std::vector<std::string>{"model", "versions", "deformation_fields", "collision_robust", "history"}));
  f.session.configure({{"algorithm", std::string("none")}});
  EXPECT_EQ(names(), (std::vector<std::string>{"model", "versions", "deformation_fields", "merge_origins", "history"}));
  const SessionReport r = f.session.report();
  EXPECT_GT(r.bytes_per_surfel, 0.0);
  EXPECT_EQ(r.surfels, static_cast<Index>(f.s.part.size()));
}

TEST(EditSession, FailuresChangeNothing) {
  Fixture f;
  const auto h = f.session.state_hash();
  const auto v = f.session.version();
  DeformParams p;
  EXPECT_THROW(f.session.deform(p), Error);                              // no regions
  EXPECT_THROW(f.session.set_regions({f.zero, {}}, {{999999}, {}}), Error);  // unknown id
  EXPECT_THROW(f.session.set_regions({f.zero, {}}, {{f.zero[0]}, {}}), Error);  // overlap
  EXPECT_THROW(f.session.set_regions({f.zero, {}}, {{}, {}}), Error);     // empty one region
  EXPECT_EQ(f.session.state_hash(), h);
  EXPECT_EQ(f.session.version(), v);
  EXPECT_FALSE(f.session.has_regions());
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  const auto h2 = f.session.state_hash();
  p.axis = Vec3::Zero();
  p.angle = 0.5;
  EXPECT_THROW(f.session.deform(p), Error);
  EXPECT_EQ(f.session.state_hash(), h2);
  EXPECT_THROW(f.session.load(SurfelModel{}), Error);
  EXPECT_EQ(f.session.state_hash(), h2);
}

}  // namespace
}  // namespace surfeledit

namespace surfeledit {
namespace {

// Sets the regions and pushes the one region 0.6 down into the zero region in six steps; the last step.
StepResult push_one_into_zero(Fixture& f) {
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  DeformParams p;
  p.translation = Vec3(0, 0, -0.1);
  StepResult o;
  for (int k = 0; k < 6; ++k) o = f.session.deform(p);
  return o;
}

TEST(EditSessionCollision, DetectsByDefaultAndReportsIds) {
  Fixture f;
  const StepResult o = push_one_into_zero(f);
  EXPECT_TRUE(o.detected);
  EXPECT_EQ(o.seq, 6u);
  EXPECT_FALSE(o.colliding.empty());
  EXPECT_EQ(o.colliding, f.session.colliding());
  EXPECT_EQ(o.depths.size(), o.colliding.size());
  EXPECT_TRUE(std::is_sorted(o.colliding.begin(), o.colliding.end()));
  for (SurfelId id : o.colliding) EXPECT_TRUE(std::binary_search(f.one.begin(), f.one.end(), id));
  EXPECT_EQ(o.stats.deformable, static_cast<Index>(f.one.size()));
  EXPECT_GT(o.stats.preprocess_ms, 0.0);
}

TEST(EditSessionCollision, ConfigureSwitchesAlgorithmWithoutTouchingTheModel) {
  Fixture f;
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  const auto h = f.session.state_hash();
  const auto v = f.session.version();
  f.session.configure({{"algorithm", std::string("temporal")}, {"threads", 1.0}});
  EXPECT_EQ(f.session.settings().collision.algorithm, CollisionAlgorithm::Temporal);
  EXPECT_EQ(f.session.state_hash(), h);
  EXPECT_EQ(f.session.version(), v);
  // A bad call changes nothing (the earlier valid setting in the same call is not applied either).
  EXPECT_THROW(f.session.configure({{"algorithm", std::string("simple")}, {"boundary_n", -1.0}}), Error);
  EXPECT_EQ(f.session.settings().collision.algorithm, CollisionAlgorithm::Temporal);
  EXPECT_EQ(f.session.settings().collision.boundary_n, 10);
  f.session.configure({{"algorithm", std::string("none")}});
  DeformParams p;
  p.translation = Vec3(0, 0, -0.6);
  const StepResult o = f.session.deform(p);
  EXPECT_FALSE(o.detected);
  EXPECT_TRUE(o.colliding.empty());
}

TEST(EditSessionCollision, RemoveKeepsIdsAndDetection) {
  Fixture f;
  StepResult o = push_one_into_zero(f);
  ASSERT_GE(o.colliding.size(), 3u);
  const IdList gone = {o.colliding[0], o.colliding[2], f.zero[5]};
  const auto v = f.session.version();
  f.session.remove(gone);
  EXPECT_EQ(f.session.version(), v + 1);
  for (SurfelId id : gone) EXPECT_EQ(f.session.model().row_of(id), -1);
  for (SurfelId id : f.session.colliding()) EXPECT_GE(f.session.model().row_of(id), 0);
  EXPECT_EQ(f.session.colliding().size(), o.colliding.size() - 2);
  const Changes c = f.session.changes_since(v);
  EXPECT_EQ(c.removed.size(), 3u);
  // Errors change nothing.
  const auto h = f.session.state_hash();
  EXPECT_THROW(f.session.remove({999999}), Error);
  IdList rest_of_one;
  for (SurfelId id : f.one)
    if (f.session.model().row_of(id) >= 0) rest_of_one.push_back(id);
  try {
    f.session.remove(rest_of_one);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Conflict);
  }
  EXPECT_EQ(f.session.state_hash(), h);
  EXPECT_EQ(f.session.version(), v + 1);
  // Detection continues on the compacted rows.
  DeformParams p;
  p.translation = Vec3(0, 0, -0.1);
  o = f.session.deform(p);
  EXPECT_TRUE(o.detected);
  EXPECT_EQ(o.stats.deformable, static_cast<Index>(f.one.size() - 2));
  for (SurfelId id : o.colliding) EXPECT_GE(f.session.model().row_of(id), 0);
}

// A session made with N threads starts every tool's detection threads at N (capped at the hardware threads,
// the setting's range), so one knob keeps a session on one core; a tool's configure() still overrides it.
TEST(EditSession, NewToolsDetectOnTheSessionsThreads) {
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int threads : {0, 1, 2, hardware, hardware + 3}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    EditSession s("t", SessionParams{threads});
    const int expected = std::min(threads, hardware);
    EXPECT_EQ(s.settings().collision.threads, expected);
    EXPECT_EQ(s.settings("another author").collision.threads, expected);  // no tool yet
    s.configure({{"threshold", 0.0}}, "another author");                 // its tool now exists
    EXPECT_EQ(s.settings("another author").collision.threads, expected);
    s.configure({{"threads", std::int64_t{0}}});
    EXPECT_EQ(s.settings().collision.threads, 0);
  }
}

TEST(EditSession, ThreadsOutsideTheirBoundAreRefused) {
  for (int threads : {-1, kMaxSessionThreads + 1, std::numeric_limits<int>::max()}) {
    const std::string message = testing_util::expect_error([&] { EditSession s("t", SessionParams{threads}); },
                                                           ErrorCode::InvalidArgument, "threads");
    EXPECT_NE(message.find(std::to_string(threads)), std::string::npos) << message;
  }
  EXPECT_NO_THROW(EditSession("t", SessionParams{kMaxSessionThreads}));
}

}  // namespace
}  // namespace surfeledit
