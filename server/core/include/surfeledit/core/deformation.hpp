// The deformation tool (docs/algorithms.md §1, Pauly et al. 2003): a zero region F0 that never moves, a
// one region F1 that moves fully, and a smooth blend in between, scaled by
//   lambda = d0 / (d0 + d1),  s = beta(lambda),
//   F(p, s) = R(axis, s * angle) (p - c) + c + s * t.
// Normals and tangent axes follow the Jacobian J = dF/dp.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <string>

#include "surfeledit/core/enum_names.hpp"
#include "surfeledit/core/types.hpp"

namespace surfeledit {

// Region label of one surfel.
enum class Region : std::uint8_t {
  Zero = 0,   // F0: rigid, never displaced
  Blend = 1,  // deformable, neither F0 nor F1
  One = 2,    // F1: fully displaced
};

enum class Blend : std::uint8_t { Smooth = 0, Quadratic = 1, Linear = 2 };

constexpr EnumNames<Blend, 3> names_of(Blend) {
  return {{{Blend::Smooth, "smooth"}, {Blend::Quadratic, "quadratic"}, {Blend::Linear, "linear"}}};
}
// Throws InvalidArgument naming `field` for a name not in names_of.
inline Blend parse_blend(const std::string& name, const std::string& field = "blend") {
  return parse_enum<Blend>(name, field);
}
inline const char* to_string(Blend blend) { return enum_name(blend); }
// beta(lambda) and its derivative d beta / d lambda, for lambda in [0, 1].
double blend_value(Blend blend, double lambda);
double blend_derivative(Blend blend, double lambda);

// One deformation step.
struct DeformParams {
  Vec3 translation = Vec3::Zero();  // t, model units
  Vec3 axis = Vec3::UnitZ();        // rotation axis (normalised internally; must be non-zero when angle != 0)
  double angle = 0.0;               // rotation angle alpha, radians
  std::optional<Vec3> center;       // c; default: centroid of F1's current positions
  Blend blend = Blend::Smooth;      // beta
};

// Bounds of one step (docs/hardening.md): the angle's magnitude, and the translation and the centre's
// distance from the model against the model's extent (bounding-box diagonal when the regions were set).
constexpr double kMaxStepAngle = 1000.0;  // radians (about 159 turns)
constexpr double kStepReach = 1e6;        // |t| and |c - box centre| at most this many extents
constexpr double kMaxCoordinate = 1e150;  // compute_fields: |coordinate| bound (squared distances stay finite)

// Throws InvalidArgument (naming the field) on non-finite values, |angle| > kMaxStepAngle, or, when
// angle != 0, an axis whose normalised length is not 1 (zero, or so large that its norm overflows,
// e.g. (1e200, 1e200, 0): a rotation about it would collapse the region to a point).
void validate(const DeformParams& params);

// Per-deformable-row data of the blend fields: one row (32 bytes) per entry of DeformationFields::deformable,
// (lambda, d lambda / dx, d lambda / dy, d lambda / dz); the gradient in 1 / model unit.
using BlendRows = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;

// Blend fields, computed once when regions are set (from the positions at that time). Only the deformable
// rows carry lambda and its gradient (F0 has lambda 0 and gradient 0 everywhere), packed contiguously in
// `deformable` order so that a step streams them instead of gathering from whole-model arrays.
struct DeformationFields {
  std::vector<Region> regions;  // #P
  IndexList deformable;         // #D rows with region != Zero, ascending
  BlendRows blend;              // #D by 4: lambda (0 < lambda <= 1; 1 on F1) and grad lambda (0 on F1) of
                                // deformable[k]; 0 rows when every deformable row is F1 (all rows are then
                                // kF1Blend, not stored: 32 bytes per deformable row saved)
  Vec3 box_centre = Vec3::Zero();  // centre of the positions' bounding box when the fields were computed
  double box_extent = std::numeric_limits<double>::infinity();  // its diagonal, model units (inf: unknown,
                                                                // no reach check)

  // The blend row (lambda, grad lambda) of deformable[k]: 4 doubles.
  const double* blend_row(std::size_t k) const { return blend.rows() == 0 ? kF1Blend : blend.data() + 4 * k; }
  // Doubles between consecutive blend rows: 4, or 0 when no row is stored (every row is kF1Blend).
  std::ptrdiff_t blend_stride() const { return blend.rows() == 0 ? 0 : 4; }
  static constexpr double kF1Blend[4] = {1.0, 0.0, 0.0, 0.0};  // an F1 row's blend: lambda 1, gradient 0

  // Dense views (#P, and #P by 3; zero on F0), for tests and inspection -- not used by the step.
  Values lambda() const;
  Points grad_lambda() const;
  // lambda of one row (0 when it is not deformable); a binary search in `deformable`.
  double lambda_of(Index row) const;
  std::size_t memory_bytes() const;
};

// validate(params), then InvalidArgument naming "translation" / "center" when |t| or the centre's
// distance from fields.box_centre exceeds kStepReach * fields.box_extent.
void validate(const DeformParams& params, const DeformationFields& fields);

// Computes lambda and its gradient with nearest-neighbour queries to F0 and F1 (k-d trees
// over each region). Throws Conflict when a surfel has d0 + d1 == 0 (it lies in both),
// InvalidArgument when F0 or F1 is empty, sizes disagree or a coordinate exceeds kMaxCoordinate.
DeformationFields compute_fields(const Points& positions, const std::vector<Region>& regions,
                                 int threads = 0);

// An upper bound (model units) on |p' - p| of every row a step of `params` moves, whatever the fields: a
// pure translation moves a row by s * t with 0 <= s <= 1, and rounding p + s * t to a double moves it by at
// most |s * t| more (p itself is a double no farther away), so 2 |t| with a margin. Empty with a rotation
// (its displacement grows with the distance from the centre; not bounded without a pass over the rows).
std::optional<double> displacement_bound(const DeformParams& params);

// What one step changed.
struct DeformResult {
  IndexList moved;     // rows whose position changed (s > 0), ascending
  Vec3 center;         // the rotation centre used
  bool finite = true;  // every new position, and every normal the step changed, is finite (checked as written)
};

// The step's kernel: Auto takes AVX2 (four rows at a time) on a CPU that has it, else Baseline (SSE2 pairs on
// x86-64). Every kernel gives the same bits (no fused multiply-adds anywhere); the choice is for tests and
// benchmarks.
enum class StepKernel : std::uint8_t { Auto = 0, Baseline = 1, Avx2 = 2 };
// Whether `kernel` runs on this CPU and build (Auto and Baseline always).
bool step_kernel_available(StepKernel kernel);

// A step that moves fewer rows runs on one thread whatever `threads` says: about a millisecond of one
// thread's work (deformation_step.cpp says why).
constexpr std::size_t kStepParallelMinMoved = 200000;

// Applies one step in place to `positions`, `normals` (#P by 3) and, when non-empty,
// the tangent axes `tangent_u`, `tangent_v` (#P by 3, lengths = radii along them), on up to `threads` threads
// (the same bits whatever the count).
// `only`, when given, restricts the step to those rows (a subset of fields.deformable, ascending); the
// others keep their state. Validates everything before touching any array (InvalidArgument naming
// "kernel" for a kernel that is not available).
DeformResult apply_step(const DeformationFields& fields, const DeformParams& params,
                        Points& positions, Points& normals, Points* tangent_u = nullptr,
                        Points* tangent_v = nullptr, int threads = 1, const IndexList* only = nullptr,
                        StepKernel kernel = StepKernel::Auto);

}  // namespace surfeledit
