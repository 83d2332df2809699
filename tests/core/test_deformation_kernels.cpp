// The deformation step's kernels (StepKernel): the AVX2 kernel (four rows at a time) gives the baseline's
// (SSE2 pairs) bits in every configuration -- each blend, with and without rotation (small angles take the
// sin/cos without range reduction, large ones with it), with and without tangents, every row or a subset
// whose lists end in every lane count -- so a journal replays to the same model on any x86-64 machine.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {

// A sphere (radius 0.5) over a slab: slab rows are F0, the sphere's top third F1, the rest blends. Tangent
// axes are random (fixed seed) so that every lane sees different values.
struct Arrays {
  Points positions, normals, tu, tv;  // #P by 3
};

struct Scene {
  Arrays arrays;
  DeformationFields fields;
};

Scene make_scene() {
  Pose above;
  above.translation = Vec3(0.0, 0.0, 0.8);
  const SampledSurfels s = make_sphere(0.5, above)->sample(SampleParams{0.03, 11, 0.25});
  const SampledSurfels b = make_box(Vec3(0.8, 0.8, 0.1))->sample(SampleParams{0.03, 11, 0.25});
  Scene sc;
  Arrays& a = sc.arrays;
  const Eigen::Index nb = b.positions.rows(), n = nb + s.positions.rows();
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  a.positions << b.positions, s.positions;
  a.normals << b.normals, s.normals;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  a.tu.resize(n, 3);
  a.tv.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j) a.tu(i, j) = u(rng), a.tv(i, j) = u(rng);
  std::vector<Region> regions(static_cast<std::size_t>(n), Region::Zero);
  for (Eigen::Index i = nb; i < n; ++i) regions[static_cast<std::size_t>(i)] = a.positions(i, 2) > 0.95 ? Region::One : Region::Blend;
  sc.fields = compute_fields(a.positions, regions);
  return sc;
}

bool same_bits(const Points& x, const Points& y) {
  return x.rows() == y.rows() && std::memcmp(x.data(), y.data(), sizeof(double) * static_cast<std::size_t>(x.size())) == 0;
}

TEST(DeformationKernels, Avx2MatchesBaselineBitForBit) {
  if (!step_kernel_available(StepKernel::Avx2)) GTEST_SKIP() << "no AVX2 on this CPU or build";
  const Scene sc = make_scene();
  ASSERT_GT(sc.fields.deformable.size(), 1000u);
  // Subsets of the deformable rows whose per-block lists leave 0, 1, 2 and 3 rows after the groups of four.
  std::vector<IndexList> subsets(4);
  for (std::size_t k = 0; k < sc.fields.deformable.size(); ++k)
    for (std::size_t m = 0; m < subsets.size(); ++m)
      if (k % (m + 2) != 0) subsets[m].push_back(sc.fields.deformable[k]);
  int compared = 0;
  for (const Blend blend : {Blend::Smooth, Blend::Quadratic, Blend::Linear}) {
    for (const double angle : {0.0, 0.05, -0.7, 2.5, -900.0}) {  // radians: no rotation, no reduction, reduction
      for (const bool tangents : {false, true}) {
        for (int subset = -1; subset < static_cast<int>(subsets.size()); ++subset) {
          DeformParams p;
          p.translation = Vec3(0.01, -0.02, 0.03);
          p.axis = Vec3(0.3, -1.0, 0.6);
          p.angle = angle;
          p.blend = blend;
          const IndexList* only = subset < 0 ? nullptr : &subsets[static_cast<std::size_t>(subset)];
          Arrays base = sc.arrays, wide = sc.arrays;
          // Two steps: the second starts from the first's results (a drag).
          for (int step = 0; step < 2; ++step) {
            const DeformResult rb = apply_step(sc.fields, p, base.positions, base.normals, tangents ? &base.tu : nullptr,
                                               tangents ? &base.tv : nullptr, 1, only, StepKernel::Baseline);
            const DeformResult rw = apply_step(sc.fields, p, wide.positions, wide.normals, tangents ? &wide.tu : nullptr,
                                               tangents ? &wide.tv : nullptr, 1, only, StepKernel::Avx2);
            ASSERT_EQ(rb.moved, rw.moved);
          }
          const std::string what = std::string(to_string(blend)) + " angle " + std::to_string(angle) +
                                   (tangents ? " tangents" : "") + " subset " + std::to_string(subset);
          EXPECT_TRUE(same_bits(base.positions, wide.positions)) << what;
          EXPECT_TRUE(same_bits(base.normals, wide.normals)) << what;
          EXPECT_TRUE(same_bits(base.tu, wide.tu)) << what;
          EXPECT_TRUE(same_bits(base.tv, wide.tv)) << what;
          // The step moved something (the comparison is not of untouched arrays).
          EXPECT_FALSE(same_bits(base.positions, sc.arrays.positions)) << what;
          ++compared;
        }
      }
    }
  }
  EXPECT_EQ(compared, 3 * 5 * 2 * 5);
}

// Auto picks an available kernel and gives its bits; an unavailable kernel is refused before anything moves.
TEST(DeformationKernels, AutoMatchesBaselineAndUnavailableKernelsAreRefused) {
  const Scene sc = make_scene();
  DeformParams p;
  p.translation = Vec3(0.0, 0.01, 0.02);
  p.axis = Vec3(1.0, 0.0, 0.0);
  p.angle = 0.3;
  Arrays base = sc.arrays, automatic = sc.arrays;
  apply_step(sc.fields, p, base.positions, base.normals, &base.tu, &base.tv, 1, nullptr, StepKernel::Baseline);
  apply_step(sc.fields, p, automatic.positions, automatic.normals, &automatic.tu, &automatic.tv, 1, nullptr);
  EXPECT_TRUE(same_bits(base.positions, automatic.positions));
  EXPECT_TRUE(same_bits(base.normals, automatic.normals));
  EXPECT_TRUE(same_bits(base.tu, automatic.tu));
  EXPECT_TRUE(step_kernel_available(StepKernel::Baseline));
  EXPECT_TRUE(step_kernel_available(StepKernel::Auto));
  Arrays m = sc.arrays;
  try {
    apply_step(sc.fields, p, m.positions, m.normals, nullptr, nullptr, 1, nullptr, static_cast<StepKernel>(7));
    ADD_FAILURE() << "accepted an unknown kernel";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "kernel");
  }
  EXPECT_TRUE(same_bits(m.positions, sc.arrays.positions));
}

}  // namespace
}  // namespace surfeledit
