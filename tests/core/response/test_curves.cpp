// Intersection curves: the 4-point rule against its formula (and its cubic reproduction for w = 1/16);
// on the analytic scenes, the curve's points lie within 1/2 spacing of the exact curve, consecutive
// points at most 3 spacings apart, every exact point within 2 spacings of the curve, closed as the
// exact curves are, one curve per contact.
#include <gtest/gtest.h>

#include <cstdio>

#include "exact_curve.hpp"
#include "surfeledit/core/response/crease.hpp"
#include "surfeledit/core/response/curves.hpp"
#include "surfeledit/core/response/merge.hpp"

namespace surfeledit {
namespace {

using testing::ResponseScene;

TEST(Curves, FourPointRuleOnASquare) {
  Curve c;
  c.closed = true;
  c.points.resize(4, 3);
  c.points << 1, 0, 0, 0, 1, 0, -1, 0, 0, 0, -1, 0;
  ASSERT_EQ(refine_curve(c, 0.5), 4);
  ASSERT_EQ(c.points.rows(), 8);
  // -w (0,-1) + (1/2 + w) ((1,0) + (0,1)) - w (-1,0) = (1/2 + 2w) (1, 1), w = 1/16.
  EXPECT_EQ(Vec3(c.points.row(1)), Vec3(0.625, 0.625, 0));
  EXPECT_EQ(Vec3(c.points.row(7)), Vec3(0.625, -0.625, 0));
  EXPECT_EQ(refine_curve(c, 0.5), 8);  // still bends 45 degrees everywhere
}

TEST(Curves, FourPointRuleReproducesCubics) {
  auto p = [](double t) { return Vec3(t, t * t * t - 2 * t * t + 0.5, 3 * t * t); };
  const Vec3 mid = four_point(p(-1), p(0), p(1), p(2));
  EXPECT_NEAR((mid - p(0.5)).norm(), 0.0, 1e-14);
}

TEST(Curves, StraightCurvesAreNotRefined) {
  Curve c;
  c.points.resize(5, 3);
  for (int i = 0; i < 5; ++i) c.points.row(i) << 0.1 * i, 0, 0;
  EXPECT_EQ(refine_curve(c, 0.1), 0);
}

void check_curves(const char* name, const ResponseScene& sc, std::size_t expected) {
  SCOPED_TRACE(name);
  const double s = sc.spacing;
  const MergeResult m = merge_regions(sc.model, sc.regions, sc.original_positions, sc.original_normals, sc.colliding);
  const CreaseResult c = crease(sc.model, m.features_deformable, m.features_zero);
  Values radii(static_cast<Eigen::Index>(c.moved.size()));
  const IndexList rows = sc.model.rows_of(c.moved, "moved");
  for (std::size_t k = 0; k < rows.size(); ++k) radii[static_cast<Eigen::Index>(k)] = sc.model.radii()[rows[k]];
  const std::vector<Curve> curves = intersection_curves(c.positions, radii);
  ASSERT_EQ(curves.size(), expected);
  const testing::ExactCurve exact = testing::exact_curve(sc);
  double longest = 0.0;
  Eigen::Index total = 0;
  for (const Curve& cv : curves) {
    EXPECT_TRUE(cv.closed);
    const Eigen::Index k = cv.points.rows();
    total += k;
    for (Eigen::Index i = 0; i + 1 < k || (cv.closed && i < k); ++i)
      longest = std::max(longest, (cv.points.row((i + 1) % k) - cv.points.row(i)).norm());
  }
  Points all(total, 3);
  Eigen::Index j = 0;
  for (const Curve& cv : curves) all.middleRows(j, cv.points.rows()) = cv.points, j += cv.points.rows();
  const double worst = testing::max_nearest_distance(all, exact.points);
  const double cover = testing::max_nearest_distance(exact.points, all);
  EXPECT_LE(worst, 0.5 * s);
  EXPECT_LE(longest, 3.0 * s);
  EXPECT_LE(cover, 2.0 * s);
  std::printf("[curves %s] %zu curve(s), %ld points, worst to exact %.3f s, longest edge %.2f s, exact->curve %.2f s\n",
              name, curves.size(), static_cast<long>(total), worst / s, longest / s, cover / s);
}

TEST(Curves, AgainstTheExactIntersection) {
  check_curves("sphere_into_box", testing::sphere_into_box(), 1);
  check_curves("arm_into_sphere", testing::arm_into_sphere(), 1);
  check_curves("ball_into_cup", testing::ball_into_cup(), 1);
  check_curves("two_contacts", testing::two_contacts(), 2);
}

TEST(Curves, NumericalExtremes) {
  for (const testing::Frame& f : testing::extreme_frames()) {
    SCOPED_TRACE("scale " + std::to_string(f.scale) + " offset " + std::to_string(f.offset.norm()));
    check_curves("sphere_into_box", testing::sphere_into_box(f), 1);
    check_curves("two_contacts", testing::two_contacts(f), 2);
  }
}

}  // namespace
}  // namespace surfeledit
