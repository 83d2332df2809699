// EditSession: versions, change tracking, lazily built structures, atomic failures.
#include <gtest/gtest.h>

#include "surfeledit/core/edit_session.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {

struct Fixture {
  SampledSurfels s = make_default_scene().sample(SampleParams{0.08, 1, 0.25});
  EditSession session{"t"};
  IdList zero, one;
  Fixture() {
    SurfelArrays a;
    a.positions = s.positions;
    a.normals = s.normals;
    a.radii = s.radii;
    session.load(SurfelModel::from_arrays(a));
    for (std::size_t i = 0; i < s.part.size(); ++i) (s.part[i] == 0 ? zero : one).push_back(i);
  }
};

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
  EXPECT_EQ(names(), (std::vector<std::string>{"model", "versions"}));
  f.session.set_regions({f.zero, {}}, {f.one, {}});
  // The default settings run the Robust detector once regions are set.
  EXPECT_EQ(names(), (std::vector<std::string>{"model", "versions", "deformation_fields", "collision_robust"}));
  f.session.configure({{"algorithm", std::string("none")}});
  EXPECT_EQ(names(), (std::vector<std::string>{"model", "versions", "deformation_fields"}));
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
