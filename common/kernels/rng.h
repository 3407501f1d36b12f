// Counter-based random numbers (docs/design.md §6): no state, a pure function of (seed, pixel, sample,
// bounce, dimension), identical on CPU and GPU.  Every structure therefore sees the same paths, and
// an RMSE between two renders measures the approximation alone, not noise.
#ifndef LS_RNG_H
#define LS_RNG_H

#include "glsl_compat.h"

#ifdef __cplusplus
namespace lsk {
#endif

// PCG-RXS-M-XS output permutation (Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 2020).
LS_FN uint pcg_hash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// A uniform float in [0, 1) with 24 random bits.
LS_FN float random01(uint seed, uint pixel, uint sample_index, uint bounce, uint dim) {
  uint h = pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample_index ^ pcg_hash(bounce * 256u + dim))));
  return float(h >> 8u) * (1.0f / 16777216.0f);
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
