// Settings by name: kinds, validation, nothing changes on error, the listing.
#include <gtest/gtest.h>

#include "surfeledit/core/settings.hpp"

namespace surfeledit {
namespace {

void expect_error(const SessionSettings& current, const std::vector<NamedSetting>& changes, const std::string& field) {
  try {
    apply_settings(current, changes);
    FAIL() << "no error for " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), field);
  }
}

TEST(Settings, DefaultsAndListingOrder) {
  const SessionSettings s;
  EXPECT_EQ(s.collision.algorithm, CollisionAlgorithm::Robust);
  const auto d = describe(s);
  std::vector<std::string> names;
  for (const auto& n : d) names.push_back(n.name);
  EXPECT_EQ(names, (std::vector<std::string>{"algorithm", "threshold", "boundary", "boundary_n", "boundary_i",
                                             "step_bound", "sphere_margin", "threads", "resample",
                                             "split_threshold", "zero_hierarchy", "deformable_hierarchy", "update",
                                             "hybrid_f", "sat", "extended", "leaf_max_surfels", "leaf_min_surfels",
                                             "max_level", "min_leaf_extent", "inflation", "knn_eps", "simplify",
                                             "cluster_size", "max_variation", "member_margin"}));
  EXPECT_EQ(std::get<std::string>(d[0].value), "robust");
  EXPECT_EQ(std::get<double>(d[3].value), 10.0);
  // The listing applied to defaults is the identity.
  const SessionSettings back = apply_settings(SessionSettings{}, d);
  EXPECT_EQ(back.collision.boundary_n, 10);
  EXPECT_EQ(back.resample.split_threshold, s.resample.split_threshold);
}

TEST(Settings, AppliesToACopy) {
  const SessionSettings s;
  const SessionSettings t = apply_settings(s, {{"algorithm", std::string("temporal")},
                                               {"boundary_n", 3.0},
                                               {"boundary_i", 2.0},
                                               {"step_bound", false},
                                               {"threshold", 0.01},
                                               {"resample", true},
                                               {"split_threshold", 2.0},
                                               {"threads", 2.0}});
  EXPECT_EQ(t.collision.algorithm, CollisionAlgorithm::Temporal);
  EXPECT_EQ(t.collision.boundary_n, 3);
  EXPECT_EQ(t.collision.boundary_i, 2);
  EXPECT_FALSE(t.collision.step_bound);
  EXPECT_EQ(t.collision.threshold, 0.01);
  EXPECT_TRUE(t.resample.enabled);
  EXPECT_EQ(t.resample.split_threshold, 2.0);
  EXPECT_EQ(t.collision.threads, 2);
  EXPECT_EQ(s.collision.algorithm, CollisionAlgorithm::Robust);  // untouched
}

TEST(Settings, TypedErrorsNameTheSetting) {
  const SessionSettings s;
  expect_error(s, {{"colour", true}}, "colour");
  expect_error(s, {{"algorithm", std::string("fastest")}}, "algorithm");
  expect_error(s, {{"algorithm", 1.0}}, "algorithm");
  expect_error(s, {{"boundary_n", std::string("ten")}}, "boundary_n");
  expect_error(s, {{"boundary_n", 2.5}}, "boundary_n");
  expect_error(s, {{"boundary_n", -1.0}}, "boundary_n");
  expect_error(s, {{"boundary_n", 3.0}}, "boundary_i");  // i = 5 > n = 3
  expect_error(s, {{"boundary", 1.0}}, "boundary");
  expect_error(s, {{"threshold", std::numeric_limits<double>::infinity()}}, "threshold");
  expect_error(s, {{"threads", -2.0}}, "threads");
  expect_error(s, {{"split_threshold", 1.0}}, "split_threshold");
  expect_error(s, {{"resample", std::string("yes")}}, "resample");
  // A later bad setting rejects the whole call.
  expect_error(s, {{"algorithm", std::string("simple")}, {"boundary_i", 0.0}}, "boundary_i");
}

// The speed/accuracy settings of issue 5: round trip through describe, typed errors, and the
// combinations approximate detection cannot serve.
TEST(Settings, SimplificationAndApproximateSearch) {
  const SessionSettings s;
  EXPECT_EQ(s.simplify.method, SimplifyMethod::None);  // nothing is clustered unless asked for
  EXPECT_EQ(s.collision.knn_eps, 0.0);
  const SessionSettings t =
      apply_settings(s, {{"algorithm", std::string("temporal")}, {"simplify", std::string("region_growing")},
                         {"cluster_size", 50.0}, {"max_variation", 0.2}, {"member_margin", 0.0}, {"knn_eps", 0.5}});
  EXPECT_EQ(t.simplify.method, SimplifyMethod::RegionGrowing);
  EXPECT_EQ(t.simplify.cluster_size, 50);
  EXPECT_EQ(t.simplify.max_variation, 0.2);
  EXPECT_EQ(t.simplify.member_margin, 0.0);
  EXPECT_EQ(t.collision.knn_eps, 0.5);
  const SessionSettings back = apply_settings(SessionSettings{}, describe(t));
  EXPECT_EQ(back.simplify.method, SimplifyMethod::RegionGrowing);
  EXPECT_EQ(back.simplify.cluster_size, 50);
  EXPECT_EQ(back.simplify.max_variation, 0.2);
  EXPECT_EQ(back.simplify.member_margin, 0.0);
  EXPECT_EQ(back.collision.knn_eps, 0.5);
  for (const char* kind : {"sphere_hierarchical", "sphere_incremental"}) {
    const SessionSettings h = apply_settings(s, {{"zero_hierarchy", std::string(kind)}});
    EXPECT_EQ(to_string(h.hierarchy.zero), std::string(kind));
    EXPECT_EQ(to_string(apply_settings(SessionSettings{}, describe(h)).hierarchy.zero), std::string(kind));
  }
  expect_error(s, {{"simplify", std::string("octree")}}, "simplify");
  expect_error(s, {{"simplify", true}}, "simplify");
  expect_error(s, {{"cluster_size", 0.0}}, "cluster_size");
  expect_error(s, {{"cluster_size", 2.5}}, "cluster_size");
  expect_error(s, {{"cluster_size", std::string("big")}}, "cluster_size");
  expect_error(s, {{"max_variation", -0.1}}, "max_variation");
  expect_error(s, {{"max_variation", 1.5}}, "max_variation");
  expect_error(s, {{"member_margin", -1.0}}, "member_margin");
  expect_error(s, {{"knn_eps", -0.5}}, "knn_eps");
  expect_error(s, {{"knn_eps", std::numeric_limits<double>::quiet_NaN()}}, "knn_eps");
  expect_error(s, {{"zero_hierarchy", std::string("sphere_tree")}}, "zero_hierarchy");
  // Combinations approximate detection cannot serve.
  expect_error(s, {{"algorithm", std::string("improved")}, {"simplify", std::string("hierarchical")}}, "simplify");
  expect_error(s, {{"zero_hierarchy", std::string("aabb")}, {"simplify", std::string("hierarchical")}}, "simplify");
  expect_error(s, {{"zero_hierarchy", std::string("sphere_incremental")}, {"simplify", std::string("hierarchical")}},
               "simplify");
  // With no detection at all, simplify is inert and accepted.
  EXPECT_NO_THROW(apply_settings(s, {{"algorithm", std::string("none")}, {"simplify", std::string("hierarchical")}}));
}

}  // namespace
}  // namespace surfeledit
