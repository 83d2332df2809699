// Deformation fields of a tool whose deformable rows are all F1 (a rigid tool, issue 14 memory): no blend
// row is stored (every one would be lambda 1, gradient 0), and a step gives the bits of the same step over
// fields that store those rows one by one -- every blend, with and without rotation and tangents, all rows
// or a subset, both kernels, two steps of a drag. Fields without stored rows are refused unless every
// deformable row is F1.
#include <gtest/gtest.h>

#include <string>

#include "deformation_model.hpp"
#include "expect_error.hpp"
#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"

namespace surfeledit {
namespace {

using deformation_model::Model;
using deformation_model::same_bits;

// The sphere over the slab: the slab is F0, the whole sphere F1.
Model make_rigid_tool_scene() { return deformation_model::sphere_over_slab(9); }

// The same fields with every deformable row's blend stored explicitly (lambda 1, gradient 0).
DeformationFields with_stored_rows(DeformationFields f) {
  f.blend = BlendRows::Zero(static_cast<Eigen::Index>(f.deformable.size()), 4);
  f.blend.col(0).setOnes();
  return f;
}

TEST(DeformationF1Fields, NoBlendRowIsStoredAndTheViewsStillSayLambdaOne) {
  const Model sc = make_rigid_tool_scene();
  const DeformationFields f = compute_fields(sc.positions, sc.regions);
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
  EXPECT_EQ(compute_fields(sc.positions, mixed).blend.rows(), static_cast<Eigen::Index>(f.deformable.size()));
}

TEST(DeformationF1Fields, StepsEqualTheStepsOverStoredRowsBitForBit) {
  const Model sc = make_rigid_tool_scene();
  const DeformationFields f = compute_fields(sc.positions, sc.regions);
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
            Model mine = sc, theirs = sc;
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
            EXPECT_FALSE(same_bits(mine.positions, sc.positions)) << what;  // the step moved rows
            ++compared;
          }
        }
      }
    }
  }
  EXPECT_EQ(compared, static_cast<int>(kernels.size()) * 3 * 4 * 2 * 2);
}

TEST(DeformationF1Fields, FieldsWithoutRowsAreRefusedUnlessEveryDeformableRowIsF1) {
  const Model sc = make_rigid_tool_scene();
  DeformationFields f = compute_fields(sc.positions, sc.regions);
  ASSERT_EQ(f.blend.rows(), 0);
  DeformParams p;
  p.translation = Vec3(0.01, 0.0, 0.0);
  // A deformable row claimed to blend, with no stored row for it.
  f.regions[static_cast<std::size_t>(f.deformable[f.deformable.size() / 2])] = Region::Blend;
  Model a = sc;
  testing_util::expect_error([&] { apply_step(f, p, a.positions, a.normals); }, ErrorCode::InvalidArgument, "fields");
  EXPECT_TRUE(same_bits(a.positions, sc.positions));
  // Stored rows that do not match the deformable list.
  DeformationFields short_rows = compute_fields(sc.positions, sc.regions);
  short_rows.blend = BlendRows::Zero(3, 4);
  testing_util::expect_error([&] { apply_step(short_rows, p, a.positions, a.normals); }, ErrorCode::InvalidArgument,
                             "fields.blend");
  EXPECT_TRUE(same_bits(a.positions, sc.positions));
}

}  // namespace
}  // namespace surfeledit
