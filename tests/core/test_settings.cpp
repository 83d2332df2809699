// Settings by name: kinds, validation, nothing changes on error, the listing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "surfeledit/core/settings.hpp"

namespace surfeledit {
namespace {

// Expects InvalidArgument naming `field`; returns the message (what()).
std::string expect_error(const SessionSettings& current, const std::vector<NamedSetting>& changes,
                         const std::string& field) {
  try {
    apply_settings(current, changes);
    ADD_FAILURE() << "no error for " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(e.field(), field) << e.what();
    return e.what();
  }
  return "";
}

TEST(Settings, DefaultsAndListingOrder) {
  const SessionSettings s;
  EXPECT_EQ(s.collision.algorithm, CollisionAlgorithm::Robust);
  const auto d = describe(s);
  std::vector<std::string> names;
  for (const auto& n : d) names.push_back(n.name);
  EXPECT_EQ(names, (std::vector<std::string>{"algorithm", "threshold", "boundary", "boundary_n", "boundary_i",
                                             "step_bound", "sphere_margin", "threads", "parallel_min_ms", "resample",
                                             "split_threshold", "zero_hierarchy", "deformable_hierarchy", "update",
                                             "hybrid_f", "sat", "extended", "leaf_max_surfels", "leaf_min_surfels",
                                             "max_level", "min_leaf_extent", "inflation", "knn_eps", "simplify",
                                             "cluster_size", "max_variation", "member_margin",
                                             // issue 9: responses and history
                                             "response", "history_mb", "backoff_epsilon",
                                             "backoff_max_iterations",
                                             // issue 13: inside modes and the swept test
                                             "inside", "winding_beta", "vote_k", "swept",
                                             // issue 10: the blend tool
                                             "blend_neighbour_factor", "blend_gamma", "blend_open_region",
                                             "blend_spring_r0"}));
  EXPECT_EQ(std::get<std::string>(d[0].value), "robust");
  EXPECT_EQ(std::get<std::int64_t>(d[3].value), 10);  // integers are listed as integers
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

// One message style for every setting: kind and range, enum names, unknown settings.
TEST(Settings, UniformMessages) {
  const SessionSettings s;
  EXPECT_EQ(expect_error(s, {{"boundary_n", 2.5}}, "boundary_n"), "boundary_n: expects an integer in [1, 256], got 2.5");
  EXPECT_EQ(expect_error(s, {{"boundary_n", std::string("ten")}}, "boundary_n"),
            "boundary_n: expects an integer in [1, 256], got 'ten'");
  EXPECT_EQ(expect_error(s, {{"max_level", std::int64_t{65}}}, "max_level"),
            "max_level: expects an integer in [0, 64], got 65");
  EXPECT_EQ(expect_error(s, {{"split_threshold", 1.0}}, "split_threshold"),
            "split_threshold: expects a finite number in (1, 1e+06], got 1");
  EXPECT_EQ(expect_error(s, {{"threshold", std::numeric_limits<double>::infinity()}}, "threshold"),
            "threshold: expects a finite number, got inf");
  EXPECT_EQ(expect_error(s, {{"boundary", 1.0}}, "boundary"), "boundary: expects a bool, got 1");
  EXPECT_EQ(expect_error(s, {{"algorithm", std::string("x")}}, "algorithm"),
            "algorithm: unknown value 'x'; expected one of none, simple, improved, temporal, robust");
  EXPECT_EQ(expect_error(s, {{"sat", true}}, "sat"), "sat: expects one of lite, full, got true");
  const std::string unknown = expect_error(s, {{"foo", 1.0}}, "foo");
  EXPECT_EQ(unknown.rfind("foo: unknown setting 'foo'; known: algorithm, threshold, boundary, ", 0), 0u) << unknown;
  EXPECT_NE(unknown.find(", member_margin"), std::string::npos) << unknown;
  // Every enum parses and prints through one name table.
  EXPECT_EQ(parse_blend("linear"), Blend::Linear);
  EXPECT_STREQ(to_string(bvh::UpdateMode::TopDown), "top_down");
  EXPECT_STREQ(to_string(static_cast<ZeroHierarchy>(99)), "unknown");
  try {
    parse_blend("sharp", "deform.blend");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "deform.blend");
    EXPECT_STREQ(e.what(), "deform.blend: unknown value 'sharp'; expected one of smooth, quadratic, linear");
  }
}

// Integer settings take integers, and integral numbers from older clients; numbers take integers.
TEST(Settings, IntegersAndNumbers) {
  const SessionSettings s;
  const SessionSettings t = apply_settings(
      s, {{"boundary_n", std::int64_t{12}}, {"cluster_size", 7.0}, {"threshold", std::int64_t{2}}});
  EXPECT_EQ(t.collision.boundary_n, 12);
  EXPECT_EQ(t.simplify.cluster_size, 7);
  EXPECT_EQ(t.collision.threshold, 2.0);
  expect_error(s, {{"threads", std::int64_t{1} << 40}}, "threads");  // beyond int
  expect_error(s, {{"boundary_n", true}}, "boundary_n");
  for (const NamedSetting& d : describe(t)) {
    const SettingSpec* spec = nullptr;
    for (const SettingSpec& row : setting_specs())
      if (d.name == row.name) spec = &row;
    ASSERT_NE(spec, nullptr) << d.name;
    const std::size_t index[] = {0, 1, 2, 3};  // variant index by kind: double, int64, bool, string
    EXPECT_EQ(d.value.index(), index[static_cast<int>(spec->kind)]) << d.name;
  }
}

// The table: unique names, every text setting with its names, defaults = SessionSettings{}.
TEST(Settings, TableDescribesEverySetting) {
  const auto& specs = setting_specs();
  EXPECT_EQ(specs.size(), 39u);  // 26 + issue 9's response, history_mb, backoff_epsilon, backoff_max_iterations
                                 // + issue 13's inside, winding_beta, vote_k, swept
                                 // + issue 10's blend_neighbour_factor, blend_gamma, blend_open_region, blend_spring_r0
                                 // + issue 14's parallel_min_ms
  const auto listed = describe(SessionSettings{});
  ASSERT_EQ(listed.size(), specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const SettingSpec& spec = specs[i];
    EXPECT_EQ(listed[i].name, spec.name);
    EXPECT_EQ(listed[i].value, default_value(spec)) << spec.name;
    EXPECT_GT(std::string(spec.doc).size(), 5u) << spec.name;
    EXPECT_EQ(spec.kind == SettingType::Text, !spec.choices.empty()) << spec.name;
    for (std::size_t j = 0; j < i; ++j) EXPECT_STRNE(spec.name, specs[j].name);
  }
  const auto threads = std::find_if(specs.begin(), specs.end(), [](const SettingSpec& x) {
    return std::string(x.name) == "threads";
  });
  ASSERT_NE(threads, specs.end());
  EXPECT_EQ(threads->kind, SettingType::Integer);
  EXPECT_EQ(threads->min, 0.0);
  EXPECT_EQ(threads->max, static_cast<double>(std::max(1u, std::thread::hardware_concurrency())));
  EXPECT_STREQ(enum_name(SettingType::Integer), "integer");
}

// Every integer setting has a finite upper bound (they size allocations, thread teams and loops), and
// threads stops at the hardware threads: 2147483647 once made libgomp abort the whole server.
TEST(Settings, IntegerSettingsAreBoundedAbove) {
  for (const SettingSpec& spec : setting_specs()) {
    if (spec.kind != SettingType::Integer) continue;
    EXPECT_TRUE(std::isfinite(spec.max)) << spec.name;
    EXPECT_LE(spec.max, 1 << 20) << spec.name;
    const SessionSettings s;
    const std::string message = expect_error(s, {{spec.name, static_cast<std::int64_t>(spec.max) + 1}}, spec.name);
    EXPECT_NE(message.find("expects an integer in"), std::string::npos) << message;
  }
  const int hw = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const SessionSettings s;
  EXPECT_EQ(apply_settings(s, {{"threads", std::int64_t{hw}}}).collision.threads, hw);
  expect_error(s, {{"threads", std::int64_t{2147483647}}}, "threads");
  expect_error(s, {{"threads", 2147483647.0}}, "threads");
  expect_error(s, {{"history_mb", 1e30}}, "history_mb");
  expect_error(s, {{"split_threshold", 1e300}}, "split_threshold");
  expect_error(s, {{"backoff_max_iterations", std::int64_t{1} << 30}}, "backoff_max_iterations");
}

}  // namespace
}  // namespace surfeledit
