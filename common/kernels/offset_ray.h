// Where a secondary ray starts: the hit point pushed off its surface along the geometric normal by a
// distance that scales with the point's magnitude (Wächter & Binder, "A Fast and Robust Method for
// Avoiding Self-Intersection", Ray Tracing Gems, 2019), instead of a fixed epsilon.  Far from the
// origin it moves a fixed number of ulps (integer arithmetic on the float bits); near the origin,
// where ulps vanish, it moves a fixed fraction of the scene's size.  The normal needs no
// normalisation (sqrt and division differ between devices): a power-of-two scale brings its largest
// component to [0.5, 1).  Both sides of the surface are handled by the caller passing the normal
// that faces the new direction.
#ifndef LS_OFFSET_RAY_H
#define LS_OFFSET_RAY_H

#include "float_bits.h"

#ifdef __cplusplus
namespace lsk {
#endif

LS_FN float offset_component(float p, float n, float near_origin, float float_scale) {
  LS_CONST float int_scale = 256.0f;
  int of_i = int(int_scale * n);
  float p_i = intBitsToFloat(floatBitsToInt(p) + (p < 0.0f ? -of_i : of_i));
  precise float p_f = p + float_scale * n;
  return abs(p) < near_origin ? p_f : p_i;
}

// scene_scale: a power of two at least the largest absolute world coordinate (DESIGN: scale-aware).
LS_FN vec3 offset_ray_origin(IN(vec3) p, IN(vec3) normal, float scene_scale) {
  float m = max_abs(normal);
  if (m == 0.0f) return p;
  vec3 n = scale_pow2(normal, unit_exponent(m) - 1);
  float near_origin = scene_scale * (1.0f / 32.0f);
  float float_scale = scene_scale * (1.0f / 65536.0f);
  return vec3(offset_component(p.x, n.x, near_origin, float_scale),
              offset_component(p.y, n.y, near_origin, float_scale),
              offset_component(p.z, n.z, near_origin, float_scale));
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
