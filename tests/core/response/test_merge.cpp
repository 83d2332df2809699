// Merge (union): against the exact signed distances of the analytic scenes, the removed set has
// precision and recall >= 0.99 (outside a band of one spacing around the other surface), no kept surfel
// lies deeper than 1/4 spacing inside the other solid, and the feature surfels and the exact
// intersection curve are within two spacings of each other; also translated by 1e6 and scaled by
// 1e-4 and 1e4.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>

#include "exact_curve.hpp"
#include "response_scenes.hpp"
#include "surfeledit/core/response/merge.hpp"

namespace surfeledit {
namespace {

using testing::ExactCurve;
using testing::Frame;
using testing::ResponseScene;

using SceneFn = std::function<ResponseScene(const Frame&)>;

MergeResult merge(const ResponseScene& sc) {
  return merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, sc.colliding);
}

std::vector<bool> flags(const SurfelModel& model, const IdList& ids) {
  std::vector<bool> f(static_cast<std::size_t>(model.size()), false);
  for (Index r : model.rows_of(ids, "ids")) f[static_cast<std::size_t>(r)] = true;
  return f;
}

void check_merge(const char* name, const ResponseScene& sc) {
  SCOPED_TRACE(name);
  const double s = sc.spacing;
  const MergeResult m = merge(sc);
  ASSERT_FALSE(sc.colliding.empty());
  const std::vector<bool> removed = flags(sc.model, m.removed);
  std::size_t tp = 0, truth = 0, found = 0, deepest_row = 0;
  double deepest = 0.0;
  for (Index r = 0; r < sc.model.size(); ++r) {
    const double d = sc.sdf_other(r);
    const bool rm = removed[static_cast<std::size_t>(r)];
    if (!rm && d < deepest) deepest = d, deepest_row = static_cast<std::size_t>(r);
    if (std::abs(d) < s) continue;  // the band around the intersection
    truth += d < 0.0;
    found += rm;
    tp += rm && d < 0.0;
  }
  const double precision = found ? double(tp) / found : 1.0, recall = truth ? double(tp) / truth : 1.0;
  EXPECT_GE(precision, 0.99);
  EXPECT_GE(recall, 0.99);
  EXPECT_GT(truth, 20u);
  EXPECT_GE(deepest, -0.25 * s) << "kept row " << deepest_row;

  const ExactCurve curve = testing::exact_curve(sc);
  ASSERT_GT(curve.points.rows(), 50);
  IdList features = m.features_deformable;
  features.insert(features.end(), m.features_zero.begin(), m.features_zero.end());
  Points fpos(static_cast<Eigen::Index>(features.size()), 3);
  const IndexList frows = sc.model.rows_of(features, "features");
  for (std::size_t k = 0; k < frows.size(); ++k) fpos.row(static_cast<Eigen::Index>(k)) = sc.model.positions().row(frows[k]);
  const double worst_feature = testing::max_nearest_distance(fpos, curve.points);
  const double worst_curve = testing::max_nearest_distance(curve.points, fpos);
  EXPECT_LE(worst_feature, 2.0 * s);
  EXPECT_LE(worst_curve, 2.0 * s);
  std::printf("[merge %s] P=%ld colliding=%zu removed=%zu (zero %d) features=%zu+%zu precision=%.4f recall=%.4f "
              "deepest kept=%.3f s, feature->curve %.2f s, curve->feature %.2f s, %.1f ms\n",
              name, static_cast<long>(sc.model.size()), sc.colliding.size(), m.removed.size(),
              m.stats.removed_zero, m.features_deformable.size(), m.features_zero.size(), precision, recall,
              deepest / s, worst_feature / s, worst_curve / s, m.stats.merge_ms);
}

struct NamedScene {
  const char* name;
  SceneFn fn;
};
const std::vector<NamedScene>& scenes() {
  static const std::vector<NamedScene> all = {
      {"sphere_into_box", [](const Frame& f) { return testing::sphere_into_box(f); }},
      {"arm_into_sphere", [](const Frame& f) { return testing::arm_into_sphere(f); }},
      {"ball_into_cup", [](const Frame& f) { return testing::ball_into_cup(f); }},
      {"two_contacts", [](const Frame& f) { return testing::two_contacts(f); }},
  };
  return all;
}

TEST(Merge, AgainstExactTruth) {
  for (const auto& s : scenes()) check_merge(s.name, s.fn(Frame{}));
}

TEST(Merge, NumericalExtremes) {
  for (const Frame& f : testing::extreme_frames()) {
    SCOPED_TRACE("scale " + std::to_string(f.scale) + " offset " + std::to_string(f.offset.norm()));
    for (const auto& s : scenes()) check_merge(s.name, s.fn(f));
  }
}

TEST(Merge, ApproximateQueriesRemoveWhatExactOnesRemove) {
  for (const auto& s : scenes()) {
    SCOPED_TRACE(s.name);
    const ResponseScene sc = s.fn(Frame{});
    MergeParams exact;
    exact.knn_eps = 0.0;
    const MergeResult a = merge(sc);
    const MergeResult b = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals,
                                        sc.colliding, exact);
    EXPECT_EQ(a.removed, b.removed);
    EXPECT_EQ(a.features_zero, b.features_zero);
  }
}

TEST(Merge, NoCollisionNoChange) {
  const ResponseScene sc = testing::sphere_into_box();
  const MergeResult m =
      merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, IdList{});
  EXPECT_TRUE(m.removed.empty());
  EXPECT_TRUE(m.features_deformable.empty());
  EXPECT_TRUE(m.features_zero.empty());
}

TEST(Merge, ValidatesInputs) {
  const ResponseScene sc = testing::sphere_into_box();
  auto field_of = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const Error& e) {
      return e.field();
    }
    return "";
  };
  const std::vector<Region> short_regions(3, Region::Zero);
  EXPECT_EQ(field_of([&] { merge_regions(sc.model, short_regions, sc.original_positions, sc.original_normals, sc.colliding); }),
            "regions");
  EXPECT_EQ(field_of([&] { merge_regions(sc.model, sc.regions, sc.original_positions, Points(), sc.colliding); }),
            "original_normals");
  EXPECT_EQ(field_of([&] { merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, IdList{0}); }),
            "colliding");  // id 0 is a zero surfel
  EXPECT_EQ(field_of([&] { merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, IdList{1u << 30}); }),
            "colliding");
  MergeParams bad;
  bad.feature_radius_factor = -1.0;
  EXPECT_EQ(field_of([&] { validate(bad); }), "feature_radius_factor");
}

}  // namespace
}  // namespace surfeledit

namespace surfeledit {
namespace {

// An open deformable region (thesis Fig. 11.1 b/c): a cap cut out of a sphere (z > 0.1), pushed up
// into a box; the rest of the sphere is zero region and stays whole, with or without closing up.
TEST(Merge, OpenRegionIsClosedWithTheOriginals) {
  const double s = 0.05, cut = 0.1;
  auto sphere = make_sphere(0.5, Pose{testing::generic_rotation(), Vec3::Zero()});
  Pose moved;
  moved.translation = Vec3(0, 0, 0.2);
  auto box = make_box(Vec3(1.0, 1.0, 0.2), Pose{Mat3::Identity(), Vec3(0, 0, 0.5 + 2 * s + 0.2)});
  SampleParams sp;
  sp.spacing = s;
  const SampledSurfels ball = sphere->sample(sp);
  SampledSurfels zero = box->sample(sp), cap;
  for (Eigen::Index i = 0; i < ball.positions.rows(); ++i) {
    SampledSurfels one;
    one.positions = ball.positions.row(i);
    one.normals = ball.normals.row(i);
    one.radii = ball.radii.segment(i, 1);
    testing::append(ball.positions(i, 2) > cut ? cap : zero, one);
  }
  testing::Motion up;
  up.translation = moved.translation;
  const ResponseScene sc = testing::build_from_samples(zero, cap, up, s);
  sphere->pose.translation = moved.translation;
  ASSERT_FALSE(sc.colliding.empty());
  const Index box_rows = static_cast<Index>(box->sample(sp).positions.rows());

  for (bool close : {true, false}) {
    MergeParams p;
    p.close_with_originals = close;
    const MergeResult m = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals,
                                        sc.colliding, p);
    const std::vector<bool> removed = flags(sc.model, m.removed);
    std::size_t sphere_zero_removed = 0, tp = 0, truth = 0, found = 0;
    for (Index r = 0; r < sc.model.size(); ++r) {
      if (sc.regions[r] != Region::Zero) continue;
      const bool rm = removed[static_cast<std::size_t>(r)];
      if (r >= box_rows) {  // the sphere's own zero surfels: all stay
        sphere_zero_removed += rm;
        continue;
      }
      const double d = sphere->sdf(sc.model.positions().row(r).transpose());
      if (std::abs(d) < s) continue;
      truth += d < 0.0;
      found += rm;
      tp += rm && d < 0.0;
    }
    std::printf("[merge open cap, closed up %d] sphere zero surfels removed %zu; box: truth %zu found %zu hit %zu\n",
                close, sphere_zero_removed, truth, found, tp);
    EXPECT_EQ(sphere_zero_removed, 0u);
    EXPECT_GT(truth, 20u);
    EXPECT_GE(double(tp) / found, 0.99);
    EXPECT_GE(double(tp) / truth, 0.99);
  }
}

}  // namespace
}  // namespace surfeledit
