// The deformation step's kernels (StepKernel): the AVX2 kernel (four rows at a time) gives the baseline's
// (SSE2 pairs) bits in every configuration -- each blend, with and without rotation (small angles take the
// sin/cos without range reduction, large ones with it), with and without tangents, every row or a subset
// whose lists end in every lane count -- so a journal replays to the same model on any x86-64 machine. The
// step's row scans (eight rows at a time with AVX2, one at a time in the baseline) refuse every bad row and
// agree on the centroid, and the kernels' finite flag agrees with the rows they wrote.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "surfeledit/core/deformation.hpp"
#include "surfeledit/core/scene.hpp"
#include "deformation_model.hpp"
#include "expect_error.hpp"

namespace surfeledit {
namespace {

using deformation_model::Model;
using deformation_model::same_bits;

// The sphere over the slab: slab rows are F0, the sphere's top third F1, the rest blends.
struct KernelScene {
  Model arrays;
  DeformationFields fields;
};

KernelScene make_kernel_scene() {
  KernelScene sc;
  Eigen::Index nb = 0;
  sc.arrays = deformation_model::sphere_over_slab(5, &nb);
  Model& a = sc.arrays;
  for (Eigen::Index i = nb; i < a.positions.rows(); ++i)
    a.regions[static_cast<std::size_t>(i)] = a.positions(i, 2) > 0.95 ? Region::One : Region::Blend;
  sc.fields = compute_fields(a.positions, a.regions);
  return sc;
}

TEST(DeformationKernels, Avx2MatchesBaselineBitForBit) {
  if (!step_kernel_available(StepKernel::Avx2)) GTEST_SKIP() << "no AVX2 on this CPU or build";
  const KernelScene sc = make_kernel_scene();
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
          Model base = sc.arrays, wide = sc.arrays;
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

// The step's scan of its rows (eight at a time with AVX2, one at a time in the baseline) refuses a bad row
// wherever it sits -- every lane of the first blocks, the middle, the last rows -- before anything moves;
// a valid row that does not move (lambda 0) leaves the step to the row-by-row pass with the same result;
// and the centroid both scans sum is the mean of F1's positions.
TEST(DeformationKernels, ScansRefuseEveryBadRowAndAgree) {
  const KernelScene sc = make_kernel_scene();
  const std::size_t count = sc.fields.deformable.size();
  ASSERT_GT(count, 100u);
  std::set<std::size_t> where;
  for (std::size_t k = 0; k < 18; ++k) where.insert(k);
  for (std::size_t k = count / 2 - 4; k < count / 2 + 5; ++k) where.insert(k);
  for (std::size_t k = count - 11; k < count; ++k) where.insert(k);
  const Eigen::Index n = sc.arrays.positions.rows();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<StepKernel> kernels{StepKernel::Baseline};
  if (step_kernel_available(StepKernel::Avx2)) kernels.push_back(StepKernel::Avx2);
  DeformParams p;
  p.translation = Vec3(0.01, -0.02, 0.03);
  p.axis = Vec3(0.3, -1.0, 0.6);
  p.angle = 0.2;
  int refused = 0;
  for (const StepKernel kernel : kernels) {
    for (const std::size_t k : where) {
      for (int kind = 0; kind < 7; ++kind) {
        DeformationFields f = sc.fields;
        const std::size_t row = static_cast<std::size_t>(f.deformable[k]);
        std::string field = "fields";
        switch (kind) {
          case 0: f.regions[row] = Region::Zero; break;
          case 1: f.blend(static_cast<Eigen::Index>(k), 0) = -0.25; break;
          case 2: f.blend(static_cast<Eigen::Index>(k), 0) = 1.5; break;
          case 3: f.blend(static_cast<Eigen::Index>(k), 0) = nan; break;
          case 4:  // equal to its predecessor, or negative for the first row
            f.deformable[k] = k > 0 ? f.deformable[k - 1] : -1;
            field = "fields.deformable";
            break;
          case 5:
            f.deformable[k] = static_cast<Index>(n);
            field = "fields.deformable";
            break;
          case 6:  // below its predecessor (a gatherable row, unlike n)
            f.deformable[k] = k > 0 ? f.deformable[k - 1] - 1 : std::numeric_limits<Index>::min();
            field = "fields.deformable";
            break;
        }
        Model a = sc.arrays;
        testing_util::expect_error([&] { apply_step(f, p, a.positions, a.normals, nullptr, nullptr, 1, nullptr, kernel); },
                                   ErrorCode::InvalidArgument, field);
        EXPECT_TRUE(same_bits(a.positions, sc.arrays.positions)) << "kind " << kind << " at " << k;
        EXPECT_TRUE(same_bits(a.normals, sc.arrays.normals)) << "kind " << kind << " at " << k;
        ++refused;
      }
    }
  }
  EXPECT_EQ(refused, static_cast<int>(kernels.size() * where.size()) * 7);

  // A blend row with lambda 0 is valid and stays where it is; both scans agree on everything else.
  DeformationFields still = sc.fields;
  std::size_t k0 = 13;  // a blend row inside a block of eight
  while (k0 + 1 < count && still.regions[static_cast<std::size_t>(still.deformable[k0])] != Region::Blend) ++k0;
  ASSERT_LT(k0 + 1, count);
  still.blend.row(static_cast<Eigen::Index>(k0)).setZero();
  std::vector<Model> results;
  std::vector<DeformResult> steps;
  for (const StepKernel kernel : kernels) {
    for (const DeformationFields* f : {&sc.fields, static_cast<const DeformationFields*>(&still)}) {
      results.push_back(sc.arrays);
      steps.push_back(apply_step(*f, p, results.back().positions, results.back().normals, nullptr, nullptr, 1, nullptr, kernel));
    }
  }
  EXPECT_EQ(steps[1].moved.size(), count - 1);
  EXPECT_EQ(steps[1].moved[k0], sc.fields.deformable[k0 + 1]);
  EXPECT_TRUE(results[1].positions.row(sc.fields.deformable[k0]) == sc.arrays.positions.row(sc.fields.deformable[k0]));
  for (std::size_t m = 2; m < steps.size(); ++m) {
    EXPECT_EQ(steps[m].moved, steps[m % 2].moved);
    EXPECT_EQ(steps[m].center, steps[m % 2].center);
    EXPECT_TRUE(same_bits(results[m].positions, results[m % 2].positions));
  }
  // The centroid against a long double sum of F1's positions.
  long double sum[3] = {0, 0, 0};
  std::size_t ones = 0;
  for (const Index i : sc.fields.deformable) {
    if (sc.fields.regions[static_cast<std::size_t>(i)] != Region::One) continue;
    for (int c = 0; c < 3; ++c) sum[c] += sc.arrays.positions(i, c);
    ++ones;
  }
  ASSERT_GT(ones, 0u);
  for (const DeformResult& r : steps)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.center(c), static_cast<double>(sum[c] / ones), 1e-14);
}

// DeformResult::finite, which the kernels compute as they write, against a pass over the moved rows: true after a
// small step, false after one whose translation overflows (positions and the blend rows' normals), for every
// kernel, with and without rotation, all rows, every second one or the F1 rows alone.
TEST(DeformationKernels, FiniteFlagAgreesWithTheRowsWritten) {
  const KernelScene sc = make_kernel_scene();
  DeformationFields fields = sc.fields;
  fields.box_extent = std::numeric_limits<double>::infinity();  // extent unknown: no reach check of the step
  std::vector<StepKernel> kernels{StepKernel::Baseline};
  if (step_kernel_available(StepKernel::Avx2)) kernels.push_back(StepKernel::Avx2);
  IndexList half, ones;  // every second deformable row; the F1 rows (without rotation: the flat path alone)
  for (std::size_t k = 0; k < sc.fields.deformable.size(); k += 2) half.push_back(sc.fields.deformable[k]);
  for (const Index r : sc.fields.deformable)
    if (sc.fields.regions[static_cast<std::size_t>(r)] == Region::One) ones.push_back(r);
  auto all_finite = [](const Model& a, const IndexList& rows) {
    for (const Index r : rows)
      if (!a.positions.row(r).allFinite() || !a.normals.row(r).allFinite()) return false;
    return true;
  };
  int checked = 0;
  for (const StepKernel kernel : kernels) {
    for (const double angle : {0.0, 0.3}) {
      for (const IndexList* only : {static_cast<const IndexList*>(nullptr), static_cast<const IndexList*>(&half),
                                    static_cast<const IndexList*>(&ones)}) {
        for (const double x : {0.01, 1.7e308}) {  // the second overflows once added to a position of 1 or more
          DeformParams p;
          p.translation = Vec3(x, 0.0, 0.0);
          p.axis = Vec3(0.0, 0.0, 1.0);
          p.angle = angle;
          Model a = sc.arrays;
          for (int step = 0; step < 2; ++step) {
            const DeformResult r = apply_step(fields, p, a.positions, a.normals, nullptr, nullptr, 1, only, kernel);
            EXPECT_EQ(r.finite, all_finite(a, r.moved)) << "x " << x << " angle " << angle << " step " << step;
            if (x > 1.0 && step == 1) EXPECT_FALSE(r.finite);
            if (x < 1.0) EXPECT_TRUE(r.finite);
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_EQ(checked, static_cast<int>(kernels.size()) * 2 * 3 * 2 * 2);
}

// Auto picks an available kernel and gives its bits; an unavailable kernel is refused before anything moves.
TEST(DeformationKernels, AutoMatchesBaselineAndUnavailableKernelsAreRefused) {
  const KernelScene sc = make_kernel_scene();
  DeformParams p;
  p.translation = Vec3(0.0, 0.01, 0.02);
  p.axis = Vec3(1.0, 0.0, 0.0);
  p.angle = 0.3;
  Model base = sc.arrays, automatic = sc.arrays;
  apply_step(sc.fields, p, base.positions, base.normals, &base.tu, &base.tv, 1, nullptr, StepKernel::Baseline);
  apply_step(sc.fields, p, automatic.positions, automatic.normals, &automatic.tu, &automatic.tv, 1, nullptr);
  EXPECT_TRUE(same_bits(base.positions, automatic.positions));
  EXPECT_TRUE(same_bits(base.normals, automatic.normals));
  EXPECT_TRUE(same_bits(base.tu, automatic.tu));
  EXPECT_TRUE(step_kernel_available(StepKernel::Baseline));
  EXPECT_TRUE(step_kernel_available(StepKernel::Auto));
  Model m = sc.arrays;
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
