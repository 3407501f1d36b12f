// The CPU's SIMD batches (xsimd) and glm's min/max on them lane by lane: what the fast tracer and the
// BVH builder compute with when their results must equal the scalar code's bit for bit.
#pragma once

#include <xsimd/xsimd.hpp>

// The hot path's helpers are inlined whatever the compiler's budget says: out of line, their SIMD
// values go through memory at every call (the ray-stream loop exceeded GCC's budget).
#define LS_ALWAYS_INLINE inline __attribute__((always_inline))
#define LS_ALWAYS_LAMBDA __attribute__((always_inline))  // after a lambda's parameter list

namespace ls {

// 4 floats: SSE2 on x86-64 (under every LINESPACE_ISA), NEON on aarch64.
#if XSIMD_WITH_SSE2
using Simd4Arch = xsimd::sse2;
#elif XSIMD_WITH_NEON64
using Simd4Arch = xsimd::neon64;
#else
#error "linespace needs SSE2 or NEON64 (xsimd)"
#endif
using Float4 = xsimd::batch<float, Simd4Arch>;
using Int4 = xsimd::batch<int32_t, Simd4Arch>;

// glm::min / glm::max lane by lane, NaN and signed-zero behaviour included (y < x ? y : x and
// x < y ? y : x).  x86's minps(a, b) is a < b ? a : b and maxps(a, b) is a > b ? a : b: with the
// operands swapped they are exactly glm's.
template <class Batch>
inline Batch glm_min(const Batch& x, const Batch& y) {
#if XSIMD_WITH_SSE2
  return xsimd::min(y, x);
#else
  return xsimd::select(y < x, y, x);
#endif
}
template <class Batch>
inline Batch glm_max(const Batch& x, const Batch& y) {
#if XSIMD_WITH_SSE2
  return xsimd::max(y, x);
#else
  return xsimd::select(x < y, y, x);
#endif
}

// Bit l set when lane l of a 4-lane mask is true.
inline unsigned lane_bits(const xsimd::batch_bool<float, Simd4Arch>& b) {
#if XSIMD_WITH_SSE2
  return unsigned(_mm_movemask_ps(b));
#else
  alignas(16) bool lanes[4];
  b.store_aligned(lanes);
  return unsigned(lanes[0]) | unsigned(lanes[1]) << 1 | unsigned(lanes[2]) << 2 | unsigned(lanes[3]) << 3;
#endif
}

inline unsigned lane_bits(const xsimd::batch_bool<int32_t, Simd4Arch>& b) {
#if XSIMD_WITH_SSE2
  return unsigned(_mm_movemask_ps(_mm_castsi128_ps(b)));
#else
  alignas(16) bool lanes[4];
  b.store_aligned(lanes);
  return unsigned(lanes[0]) | unsigned(lanes[1]) << 1 | unsigned(lanes[2]) << 2 | unsigned(lanes[3]) << 3;
#endif
}

#if XSIMD_WITH_AVX
// Bit l set when lane l of an 8-lane AVX mask is true.
inline unsigned lane_bits(const xsimd::batch_bool<float, xsimd::avx>& b) { return unsigned(_mm256_movemask_ps(b)); }
#endif

}  // namespace ls
