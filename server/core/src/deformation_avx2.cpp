// The deformation step's kernel four rows at a time (AVX2; deformation_kernel.hpp). This file alone is built
// with -mavx2 (and without fused multiply-adds, so the bits are the baseline's); apply_step calls it only on
// a CPU that has AVX2 (step_kernel_available).
#include "deformation_kernel.hpp"

namespace surfeledit::detail {

#if defined(__AVX2__) && !defined(__FMA__)
BlockFn avx2_block(Blend blend, bool rotate, bool tangents) { return pick_block<D4>(blend, rotate, tangents); }
#else
BlockFn avx2_block(Blend, bool, bool) { return nullptr; }
#endif

}  // namespace surfeledit::detail
