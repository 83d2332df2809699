// A session's hierarchy settings: every refused combination names its setting (bvh/hierarchy_validate.cpp).
#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "surfeledit/core/settings.hpp"

using namespace surfeledit;

TEST(CollisionBvh, SettingsErrorsNameTheSetting) {
  SessionSettings s;
  auto fails = [&](std::vector<NamedSetting> changes, const std::string& field) {
    try {
      apply_settings(s, changes);
      ADD_FAILURE() << "no error for " << field;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  fails({{"zero_hierarchy", std::string("kdop")}}, "zero_hierarchy");
  fails({{"deformable_hierarchy", std::string("obb")}}, "deformable_hierarchy");
  fails({{"deformable_hierarchy", std::string("aabb")}}, "deformable_hierarchy");  // no zero tree
  fails({{"zero_hierarchy", std::string("aabb")}, {"update", std::string("sideways")}}, "update");
  fails({{"zero_hierarchy", std::string("aabb")}, {"hybrid_f", 1.5}}, "hybrid_f");
  fails({{"zero_hierarchy", std::string("obb")}, {"sat", std::string("half")}}, "sat");
  fails({{"extended", true}}, "extended");  // no zero tree
  fails({{"zero_hierarchy", std::string("aabb")}, {"extended", true}, {"algorithm", std::string("simple")}}, "extended");
  fails({{"zero_hierarchy", std::string("aabb")}, {"algorithm", std::string("improved")}}, "zero_hierarchy");
  fails({{"zero_hierarchy", std::string("aabb")}, {"algorithm", std::string("simple")}, {"step_bound", false}},
        "zero_hierarchy");
  fails({{"leaf_max_surfels", 1.0}, {"leaf_min_surfels", 2.0}}, "leaf_max_surfels");
  fails({{"leaf_min_surfels", 0.0}}, "leaf_min_surfels");
  fails({{"leaf_max_surfels", 2.5}}, "leaf_max_surfels");
  fails({{"inflation", -1.0}}, "inflation");
  const SessionSettings ok = apply_settings(
      s, {{"zero_hierarchy", std::string("obb")}, {"deformable_hierarchy", std::string("aabb")},
          {"update", std::string("top_down")}, {"sat", std::string("full")}, {"leaf_max_surfels", 8.0}});
  EXPECT_EQ(ok.hierarchy.zero, ZeroHierarchy::Obb);
  EXPECT_EQ(ok.hierarchy.tree.update, bvh::UpdateMode::TopDown);
  EXPECT_EQ(ok.hierarchy.tree.leaf_max_surfels, 8);
  bool listed = false;
  for (const auto& d : describe(ok))
    if (d.name == "zero_hierarchy") listed = std::get<std::string>(d.value) == "obb";
  EXPECT_TRUE(listed);
}
