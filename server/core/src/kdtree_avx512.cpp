// The AVX2 leaf scans and walk (kdtree_avx2.cpp) built for AVX-512: the same source and the same operations per lane
// (no FMA, so the same bits), which the compiler turns into compares into mask registers, masked moves instead of
// two-micro-op blends, and 32 vector registers (Robust and Temporal detects 1.04-1.05x on an AVX-512 Xeon), plus the
// parts written for it under __AVX512F__ there: the k = 1 scan eight points and the fan's eight cells per vector
// (1.02x more; RESULTS §73). KdTree picks it on CPUs with AVX-512F, VL and DQ (kd_scan_available); built without those flags (another
// compiler or target), avx512_search() is nullptr.
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512DQ__)
#define SURFELEDIT_KD_ENTRY avx512_search
// GCC 12's AVX-512 intrinsics (_mm512_cvtps_pd, _mm512_reduce_min_pd) fill their unused pass-through operand with
// _mm512_undefined_pd(), which -Wmaybe-uninitialized reports at every use; nothing of ours is uninitialised.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "kdtree_avx2.cpp"
#else
#include "kdtree_walk.hpp"
namespace surfeledit::kd {
const SearchFns* avx512_search() { return nullptr; }
}  // namespace surfeledit::kd
#endif
