// What the multigrid's files share (multigrid.h's Multigrid is split by seam:
// multigrid_blocks.cc, the block-sparse storage and its products; multigrid_build.cc, the
// hierarchy's construction; multigrid.cc, the smoothers and the V-cycle).
#ifndef FEMREG_SOLVERS_FAST_MULTIGRID_INTERNAL_H_
#define FEMREG_SOLVERS_FAST_MULTIGRID_INTERNAL_H_

#include <cstdint>
#include <cstring>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace femreg {
namespace fast_backend {
namespace multigrid_internal {

// Products and block Jacobi run in parallel from this many unknowns on: a V-cycle has ~15 of them,
// each worth a team's start from here (docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr int kParallelUnknowns = 4096;
// Element-wise passes go to the team from this many entries per thread on (the finest
// matrix's values to bfloat16; the smoother's vector updates, lighter each): below, the team's
// start costs more than the pass waits on memory. The conversion only runs with the hierarchy,
// from 5k vertices on.
constexpr int64_t kParallelEntries = int64_t{1} << 18;
constexpr int64_t kParallelVectorEntries = int64_t{1} << 14;
// ... or this many stored entries: a coarse level has few unknowns, but many entries per
// column (docs/notes/2026-11-28-figures-from-code-comments.md).
constexpr int64_t kParallelNonzeros = 65536;

// Level 0's values as the V-cycle reads them: from[0, n) rounded to float, then to bfloat16
// (float's range, 8 significant bits; to nearest, ties to even) into half (ToBfloat16 each).
// The level-0 product then streams 2 bytes a value instead of 4: the V-cycle only
// approximates A^-1 (PCG, in double with A itself, corrects it), and at 8 bits it does so
// about as well (docs/notes/2026-12-05-bfloat16-level-0.md).
void RoundToBfloat16(const double* from, int64_t n, int threads, uint16_t* half);

// One value as RoundToBfloat16 rounds it, and back to float (exactly).
inline uint16_t ToBfloat16(double value) {
  const float f = static_cast<float>(value);
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  if ((bits & 0x7f800000u) == 0x7f800000u) {
    bits |= (bits & 0x007fffffu) != 0 ? 0x00400000u : 0u;  // a NaN stays one
  } else {
    bits += 0x7fffu + ((bits >> 16) & 1u);  // to nearest, ties to even
  }
  return static_cast<uint16_t>(bits >> 16);
}
inline float FromBfloat16(uint16_t half) {
  const uint32_t bits = static_cast<uint32_t>(half) << 16;
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

#ifdef __SSE2__
// Four (two, the upper lanes 0) bfloat16 values at h as floats, FromBfloat16 lane by lane:
// each value moves to the upper half of its 32-bit lane.
inline __m128 LoadBfloat16x4(const uint16_t* h) {
  const __m128i raw = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(h));
  return _mm_castsi128_ps(_mm_unpacklo_epi16(_mm_setzero_si128(), raw));
}
inline __m128 LoadBfloat16x2(const uint16_t* h) {
  int32_t two;
  std::memcpy(&two, h, sizeof two);
  return _mm_castsi128_ps(_mm_unpacklo_epi16(_mm_setzero_si128(), _mm_cvtsi32_si128(two)));
}
#endif

}  // namespace multigrid_internal
}  // namespace fast_backend
}  // namespace femreg

#endif  // FEMREG_SOLVERS_FAST_MULTIGRID_INTERNAL_H_
