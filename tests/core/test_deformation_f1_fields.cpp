// Deformation fields of a tool whose deformable rows are all F1 (a rigid tool, issue 14 memory): no blend
// row is stored (every one would be lambda 1, gradient 0), and a step gives the bits of the same step over
// fields that store those rows one by one -- every blend, with and without rotation and tangents, all rows
// or a subset, both kernels, two steps of a drag. Fields without stored rows are refused unless every
// deformable row is F1.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>

#include "expect_error.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {

struct Arrays {
  Points positions, normals, tu, tv;  // #P by 3
};

// A sphere (radius 0.5) over a slab: the slab is F0, the whole sphere F1. Random tangent axes (fixed seed).
struct RigidToolScene {
  Arrays arrays;
  std::vector<Region> regions;  // #P
};

RigidToolScene make_scene() {
  Pose above;
  above.translation = Vec3(0.0, 0.0, 0.8);
  const SampledSurfels s = make_sphere(0.5, above)->sample(SampleParams{0.03, 11, 0.25});
  const SampledSurfels b = make_box(Vec3(0.8, 0.8, 0.1))->sample(SampleParams{0.03, 11, 0.25});
  RigidToolScene sc;
  Arrays& a = sc.arrays;
  const Eigen::Index nb = b.positions.rows(), n = nb + s.positions.rows();
  a.positions.resize(n, 3);
  a.normals.resize(n, 3);
  a.positions << b.positions, s.positions;
  a.normals << b.normals, s.normals;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-0.02, 0.02);
  a.tu.resize(n, 3);
  a.tv.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j) a.tu(i, j) = u(rng), a.tv(i, j) = u(rng);
  sc.regions.assign(static_cast<std::size_t>(n), Region::Zero);
  for (Eigen::Index i = nb; i < n; ++i) sc.regions[static_cast<std::size_t>(i)] = Region::One;
  return sc;
}

bool same_bits(const Points& x, const Points& y) {
  return x.rows() == y.rows() && std::memcmp(x.data(), y.data(), sizeof(double) * static_cast<std::size_t>(x.size())) == 0;
}

// The same fields with every deformable row's blend stored explicitly (lambda 1, gradient 0).
DeformationFields with_stored_rows(DeformationFields f) {
  f.blend = BlendRows::Zero(static_cast<Eigen::Index>(f.deformable.size()), 4);
  f.blend.col(0).setOnes();
  return f;
}

TEST(DeformationF1Fields, NoBlendRowIsStoredAndTheViewsStillSayLambdaOne) {
  const RigidToolScene sc = make_scene();
  const DeformationFields f = compute_fields(sc.arrays.positions, sc.regions);
  ASSERT_GT(f.deformable.size(), 1000u);
  EXPECT_EQ(f.blend.rows(), 0);
  const DeformationFields copy = f;  // capacities as the copy below has them
  const DeformationFields stored = with_stored_rows(f);
  EXPECT_EQ(stored.memory_bytes() - copy.memory_bytes(), 32 * f.deformable.size());
  const Values lambda = f.lambda();
  const Points grad = f.grad_lambda();
  for (std::size_t r = 0; r < sc.regions.size(); ++r) {
    const double expect = sc.regions[r] == Region::One ? 1.0 : 0.0;
    EXPECT_EQ(lambda[static_cast<Eigen::Index>(r)], expect) << r;
    EXPECT_EQ(f.lambda_of(static_cast<Index>(r)), expect) << r;
    EXPECT_TRUE(grad.row(static_cast<Eigen::Index>(r)).isZero()) << r;
  }
  // One region that blends: every row is stored again.
  std::vector<Region> mixed = sc.regions;
  mixed.back() = Region::Blend;
  EXPECT_EQ(compute_fields(sc.arrays.positions, mixed).blend.rows(), static_cast<Eigen::Index>(f.deformable.size()));
}

TEST(DeformationF1Fields, StepsEqualTheStepsOverStoredRowsBitForBit) {
  const RigidToolScene sc = make_scene();
  const DeformationFields f = compute_fields(sc.arrays.positions, sc.regions);
  ASSERT_EQ(f.blend.rows(), 0);
  const DeformationFields stored = with_stored_rows(f);
  IndexList subset;  // every third deformable row: lists that end in every lane count
  for (std::size_t k = 0; k < f.deformable.size(); ++k)
    if (k % 3 != 0) subset.push_back(f.deformable[k]);
  std::vector<StepKernel> kernels{StepKernel::Baseline};
  if (step_kernel_available(StepKernel::Avx2)) kernels.push_back(StepKernel::Avx2);
  int compared = 0;
  for (const StepKernel kernel : kernels) {
    for (const Blend blend : {Blend::Smooth, Blend::Quadratic, Blend::Linear}) {
      for (const double angle : {0.0, 0.05, -0.7, 2.5}) {
        for (const bool tangents : {false, true}) {
          for (const bool part : {false, true}) {
            DeformParams p;
            p.translation = Vec3(0.01, -0.02, 0.03);
            p.axis = Vec3(0.3, -1.0, 0.6);
            p.angle = angle;
            p.blend = blend;
            Arrays mine = sc.arrays, theirs = sc.arrays;
            for (int step = 0; step < 2; ++step) {
              const DeformResult a = apply_step(f, p, mine.positions, mine.normals, tangents ? &mine.tu : nullptr,
                                                tangents ? &mine.tv : nullptr, 1, part ? &subset : nullptr, kernel);
              const DeformResult b = apply_step(stored, p, theirs.positions, theirs.normals,
                                                tangents ? &theirs.tu : nullptr, tangents ? &theirs.tv : nullptr, 1,
                                                part ? &subset : nullptr, kernel);
              ASSERT_EQ(a.moved, b.moved);
              ASSERT_EQ(a.center, b.center);
            }
            const std::string what = std::string(to_string(blend)) + " angle " + std::to_string(angle) +
                                     (tangents ? " tangents" : "") + (part ? " subset" : "") +
                                     (kernel == StepKernel::Avx2 ? " avx2" : " baseline");
            EXPECT_TRUE(same_bits(mine.positions, theirs.positions)) << what;
            EXPECT_TRUE(same_bits(mine.normals, theirs.normals)) << what;
            EXPECT_TRUE(same_bits(mine.tu, theirs.tu)) << what;
            EXPECT_TRUE(same_bits(mine.tv, theirs.tv)) << what;
            EXPECT_FALSE(same_bits(mine.positions, sc.arrays.positions)) << what;  // the step moved rows
            ++compared;
          }
        }
      }
    }
  }
  EXPECT_EQ(compared, static_cast<int>(kernels.size()) * 3 * 4 * 2 * 2);
}

TEST(DeformationF1Fields, FieldsWithoutRowsAreRefusedUnlessEveryDeformableRowIsF1) {
  const RigidToolScene sc = make_scene();
  DeformationFields f = compute_fields(sc.arrays.positions, sc.regions);
  ASSERT_EQ(f.blend.rows(), 0);
  DeformParams p;
  p.translation = Vec3(0.01, 0.0, 0.0);
  // A deformable row claimed to blend, with no stored row for it.
  f.regions[static_cast<std::size_t>(f.deformable[f.deformable.size() / 2])] = Region::Blend;
  Arrays a = sc.arrays;
  testing_util::expect_error([&] { apply_step(f, p, a.positions, a.normals); }, ErrorCode::InvalidArgument, "fields");
  EXPECT_TRUE(same_bits(a.positions, sc.arrays.positions));
  // Stored rows that do not match the deformable list.
  DeformationFields short_rows = compute_fields(sc.arrays.positions, sc.regions);
  short_rows.blend = BlendRows::Zero(3, 4);
  testing_util::expect_error([&] { apply_step(short_rows, p, a.positions, a.normals); }, ErrorCode::InvalidArgument,
                             "fields.blend");
  EXPECT_TRUE(same_bits(a.positions, sc.arrays.positions));
}

}  // namespace
}  // namespace surfeledit
