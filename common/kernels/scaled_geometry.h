// Triangle areas, unit normals and squared distances at any float scale.  World coordinates of 1e20
// square to 1e40 (past float's 3.4e38) and those of 1e-20 to 1e-40 (denormal, then zero), so the
// light-sampling arithmetic of the path tracer works in *scene units*: lengths multiplied by 2^k,
// k = unit_exponent(scene scale), which brings the scene's extent to [1, 2).  Ratios such as
// pdf = distance^2 / (cos * area) are the same in any unit, so nothing but the range changes.
// Every scaling is by a power of two (float_bits.h), hence exact.
#ifndef LS_SCALED_GEOMETRY_H
#define LS_SCALED_GEOMETRY_H

#include "float_bits.h"

#ifdef __cplusplus
namespace lsk {
#endif

// Area of triangle (p0, p1, p2) in scene units (world area * 4^k) and its unit normal (zero when the
// triangle is degenerate).  The edges are first brought to [1, 2) by their own power of two, so the
// cross product neither overflows nor underflows; the area is then moved to scene units.
LS_FN float triangle_area_scaled(IN(vec3) p0, IN(vec3) p1, IN(vec3) p2, int k, OUT(vec3) unit_normal) {
  vec3 e1 = p1 - p0;
  vec3 e2 = p2 - p0;
  int j = unit_exponent(max(max_abs(e1), max_abs(e2)));
  vec3 c = cross(scale_pow2(e1, j), scale_pow2(e2, j));
  float len = length(c);
  if (!(len > 0.0f) || isinf(len)) {
    unit_normal = vec3(0.0f);
    return 0.0f;
  }
  unit_normal = c / len;
  // 0.5 * len is the area at scale 2^j; world area = that * 4^-j; scene units: * 4^k.
  return scale_pow2(scale_pow2(0.5f * len, k - j), k - j);
}

// v / |v| for any finite non-zero v: |v| of a 1e20-long vector overflows (its square is 1e40) and
// that of a 1e-25-long one underflows, so v is first brought to [1, 2) by a power of two.  Zero
// stays zero.
LS_FN vec3 normalize_any(IN(vec3) v) {
  float m = max_abs(v);
  if (!(m > 0.0f)) return vec3(0.0f);
  return normalize_in_order(scale_pow2(v, unit_exponent(m)));
}

// A world-space vector in scene units (exact: a power-of-two scale).
LS_FN vec3 to_scene_units(IN(vec3) v, int k) { return scale_pow2(v, k); }
LS_FN float to_scene_units(float x, int k) { return scale_pow2(x, k); }

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
