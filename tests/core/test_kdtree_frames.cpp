// KdTreeParams::frames (an oriented box per node, kdtree_build.cpp's build_frames): samples of planes and a cylinder
// turned against the axes, where the oriented boxes are kept and prune, queried near and far from the surface at
// 1e6 offsets and 1e+-4 scales. A tree with frames answers nearest, nearest_from (from every leaf) and knn(., 1)
// with the same row and dist2 bits as the same tree without frames, and its distance is the brute-force minimum.
#include <gtest/gtest.h>

#include <vector>

#include "kdtree_truth.hpp"
#include "surfeledit/core/kdtree.hpp"

namespace surfeledit {
namespace {

TEST(KdTreeFrames, SameAnswersAsWithoutFramesAndBruteForceOnTurnedSurfaces) {
  const double h = 0.01;
  for (const bool bent : {false, true}) {
    for (const double scale : {1e-4, 1.0, 1e4}) {
      for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
        const Points pts = test::turned_surface(90, h, bent, scale, offset);
        const Points queries = test::queries_about(pts, 120, h, scale);
        for (const KdScan scan : {KdScan::Scalar, KdScan::Auto}) {
          const KdTree with(pts, test::nearest_params(scan, true, false)), without(pts, test::nearest_params(scan, false, false));
          ASSERT_GT(with.memory_bytes(), without.memory_bytes());  // the frames are there
          const KnnResult batch_with = with.knn(queries, 1), batch_without = without.knn(queries, 1);
          for (Eigen::Index i = 0; i < queries.rows(); ++i) {
            const Vec3 q = queries.row(i).transpose();
            double dw = 0.0, dn = 0.0;
            const Index rw = with.nearest(q, &dw), rn = without.nearest(q, &dn);
            ASSERT_EQ(rw, rn) << "query " << i;
            ASSERT_EQ(dw, dn) << "query " << i;  // bit-identical
            ASSERT_EQ(batch_with.indices(i, 0), rn);
            ASSERT_EQ(batch_with.dist2(i, 0), batch_without.dist2(i, 0));
            // Brute force, relative to the offset so that the comparison is between small differences.
            const std::vector<double> truth = test::brute_dist2(pts.rowwise() - offset.transpose(), q - offset);
            EXPECT_NEAR(dw, truth.front(), 1e-9 * truth.front() + 1e-24 * scale * scale) << "query " << i;
            // From several leaves: the first, the winner's, and a stale one.
            for (std::uint32_t start : {0u, 7u, 1000000u}) {
              std::uint32_t lw = start, ln = start;
              double fw = 0.0, fn = 0.0;
              ASSERT_EQ(with.nearest_from(q, lw, &fw), rn) << "query " << i << " start " << start;
              ASSERT_EQ(without.nearest_from(q, ln, &fn), rn);
              ASSERT_EQ(fw, fn);
              ASSERT_EQ(lw, ln);
            }
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace surfeledit
