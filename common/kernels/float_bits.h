// Exact power-of-two scaling.  Multiplying by 2^k is exact in IEEE arithmetic (barring overflow and
// denormals), so scaling inputs into [1, 2) keeps the products of the triangle test far from both
// overflow (1e20 coordinates) and underflow (1e-20 coordinates) without changing any decision.
#ifndef LS_FLOAT_BITS_H
#define LS_FLOAT_BITS_H

#include "glsl_compat.h"

#ifdef __cplusplus
namespace lsk {
#endif

LS_FN float ls_infinity() { return uintBitsToFloat(0x7F800000u); }

// Unbiased binary exponent of a finite, non-zero x (denormals report -127).
LS_FN int float_exponent(float x) { return ((floatBitsToInt(x) >> 23) & 255) - 127; }

// The k that brings max(|x|) into [1, 2): x * 2^k.  0 for x == 0.
LS_FN int unit_exponent(float m) {
  if (m == 0.0f) return 0;
  return clamp(-float_exponent(m), -126, 126);
}

// 2^e for e in [-126, 127], built from its bits (exact, and cheaper than ldexp).
LS_FN float pow2(int e) { return intBitsToFloat((e + 127) << 23); }

// x * 2^e, saturating to +-inf above the float range and flushing to 0 below it (GLSL leaves ldexp
// undefined there); exact otherwise.  A normal x with a normal result only changes its exponent
// field, which is set directly (what the multiplication gives, without the two multiplications).
// Otherwise: two multiplications by halves of e keep each factor in range, and since both move x
// the same way the intermediate stays between x and the result.
LS_FN float scale_pow2(float x, int e) {
  int bits = floatBitsToInt(x);
  int field = (bits >> 23) & 255;
  if (field != 0 && field != 255 && field + e >= 1 && field + e <= 254)
    return intBitsToFloat((bits & int(0x807FFFFFu)) | ((field + e) << 23));
  if (x == 0.0f || isinf(x) || isnan(x)) return x;
  int ex = float_exponent(x);
  if (ex + e > 127) return x < 0.0f ? -ls_infinity() : ls_infinity();
  if (ex + e < -126) return 0.0f * x;
  int e1 = e / 2;
  return (x * pow2(e1)) * pow2(e - e1);
}

LS_FN vec3 scale_pow2(IN(vec3) v, int e) { return vec3(scale_pow2(v.x, e), scale_pow2(v.y, e), scale_pow2(v.z, e)); }

// -0 as +0, decided on the bits: shader compilers may fold `x + 0.0f` to `x` (NIR does, even under
// `precise`), so that idiom leaves -0 on the GPU where the CPU gives +0.
LS_FN float positive_zero(float x) { return floatBitsToUint(x) == 0x80000000u ? 0.0f : x; }

// a.x*b.x + a.y*b.y + a.z*b.z summed left to right.  GLSL leaves the order (and fusion) inside dot()
// to the implementation and GLM sums a vec4 dot in pairs, so deciding arithmetic spells sums out.
LS_FN float dot_in_order(IN(vec3) a, IN(vec3) b) {
  precise float s = a.x * b.x;
  s = s + a.y * b.y;
  s = s + a.z * b.z;
  return s;
}

// GLM's cross, length and normalize (v * (1 / sqrt(dot))) spelled out: GLSL's built-ins may be
// evaluated otherwise (lavapipe's normalize uses an approximate inverse square root).
LS_FN vec3 cross_in_order(IN(vec3) a, IN(vec3) b) {
  precise float x = a.y * b.z - b.y * a.z;
  precise float y = a.z * b.x - b.z * a.x;
  precise float z = a.x * b.y - b.x * a.y;
  return vec3(x, y, z);
}

LS_FN float length_in_order(IN(vec3) v) { return sqrt(dot_in_order(v, v)); }

LS_FN vec3 normalize_in_order(IN(vec3) v) {
  precise float inv = 1.0f / sqrt(dot_in_order(v, v));
  precise vec3 r = v * inv;
  return r;
}

// v[i] for i in 0..2, spelled as selects: C++'s glm::vec3 indexes through a switch.
LS_FN float component(IN(vec3) v, uint i) { return i == 0u ? v.x : (i == 1u ? v.y : v.z); }

LS_FN float max_abs(IN(vec3) v) { return max(max(abs(v.x), abs(v.y)), abs(v.z)); }

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
