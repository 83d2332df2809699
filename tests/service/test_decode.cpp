// Decoding of the generated C request types into the core's types (decode.hpp).
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "service_test_support.hpp"
#include "surfeledit/service/decode.hpp"

using namespace surfeledit;
using namespace surfeledit::service;
using namespace surfeledit::service::test;

TEST(Decode, Selectors) {
  surfeledit_proto_Selector s{};
  s.kind = surfeledit_proto_SELECTOR_BOX;
  s.center = {1, 2, 3};
  s.half_extents = {0.5, 0.5, 0.5};
  const Selector box = to_core(s, "set_regions.one.selectors[0]");
  EXPECT_EQ(box.kind, Selector::Kind::Box);
  EXPECT_EQ(box.center, Vec3(1, 2, 3));
  EXPECT_EQ(box.half_extents, Vec3(0.5, 0.5, 0.5));

  s.kind = static_cast<surfeledit_proto_SelectorKind>(7);
  expect_error([&] { to_core(s, "sel"); }, ErrorCode::InvalidArgument, "sel.kind");
  s.kind = surfeledit_proto_SELECTOR_SPHERE;
  s.radius = -1.0;
  expect_error([&] { to_core(s, "sel"); }, ErrorCode::InvalidArgument, "sel");
}

TEST(Decode, RegionSpecs) {
  std::vector<uint64_t> ids = {3, 1, 2};
  std::vector<surfeledit_proto_Selector> sels(2);
  sels[0].kind = surfeledit_proto_SELECTOR_SPHERE;
  sels[0].radius = 1.0;
  sels[1].kind = surfeledit_proto_SELECTOR_SPHERE;
  sels[1].radius = std::numeric_limits<double>::infinity() * 0.0;  // NaN
  surfeledit_proto_RegionSpec r{};
  point_to(r.ids, ids);
  r.selectors._length = 1;
  r.selectors._buffer = sels.data();
  const RegionSpec spec = to_core(r, "set_regions.zero");
  EXPECT_EQ(spec.ids, (IdList{3, 1, 2}));
  ASSERT_EQ(spec.selectors.size(), 1u);
  EXPECT_DOUBLE_EQ(spec.selectors[0].radius, 1.0);
  r.selectors._length = 2;
  expect_error([&] { to_core(r, "set_regions.zero"); }, ErrorCode::InvalidArgument, "set_regions.zero.selectors[1]");
}

TEST(Decode, DeformParams) {
  surfeledit_proto_Deform d{};
  d.translation = {0, 0, 1};
  d.axis = {0, 1, 0};
  d.angle = 0.5;
  std::string blend;
  d.blend = const_cast<char*>(blend.c_str());
  DeformParams p = to_core(d, "deform");
  EXPECT_EQ(p.blend, Blend::Smooth);  // empty -> smooth
  EXPECT_FALSE(p.center.has_value());
  EXPECT_EQ(p.translation, Vec3(0, 0, 1));
  blend = "linear";
  d.blend = const_cast<char*>(blend.c_str());
  d.has_center = true;
  d.center = {1, 1, 1};
  p = to_core(d, "deform");
  EXPECT_EQ(p.blend, Blend::Linear);
  ASSERT_TRUE(p.center.has_value());
  EXPECT_EQ(*p.center, Vec3(1, 1, 1));
  blend = "wobbly";
  d.blend = const_cast<char*>(blend.c_str());
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.blend");
  blend = "smooth";
  d.blend = const_cast<char*>(blend.c_str());
  d.axis = {0, 0, 0};
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.");
  d.axis = {0, 0, 1};
  d.translation.x = std::numeric_limits<double>::quiet_NaN();
  expect_error([&] { to_core(d, "deform"); }, ErrorCode::InvalidArgument, "deform.");
}
