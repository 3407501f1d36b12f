// Conservative ray/box test (Ize, "Robust BVH Ray Traversal", JCGT 2013).  It decides nothing about
// which triangle is hit: it only prunes, and it never prunes a box the ray touches, so the inexact
// reciprocal of a GPU cannot change a result.  The far distance is widened by 2*gamma(3) to absorb
// the three roundings of (bound - origin) * inv_dir.  Boxes are closed: a ray running along a face
// or an edge, or a flat (zero-thickness) box, counts as entering it.
#ifndef LS_RAY_BOX_H
#define LS_RAY_BOX_H

#include "glsl_compat.h"

#ifdef __cplusplus
namespace lsk {
#endif

// Reciprocal direction without infinities: a zero or denormal component (whose reciprocal would
// overflow) gets a huge finite value of its sign, so (bound - origin) * inv is never 0 * inf = NaN.
LS_FN float safe_reciprocal1(float d) {
  LS_CONST float big = 3.0e38f;
  LS_CONST float min_normal = 1.17549435e-38f;
  return abs(d) < min_normal ? (d < 0.0f ? -big : big) : 1.0f / d;
}

LS_FN vec3 safe_reciprocal(IN(vec3) d) {
  return vec3(safe_reciprocal1(d.x), safe_reciprocal1(d.y), safe_reciprocal1(d.z));
}

// t pushed outwards by 2*gamma(3) of its magnitude, the error bound of a slab distance.
LS_FN float widen_distance(float t) {
  LS_CONST float two_gamma3 = 2.0f * (3.0f * 5.9604645e-8f) / (1.0f - 3.0f * 5.9604645e-8f);
  precise float w = t + abs(t) * two_gamma3;
  return w;
}

// True when [tmin, tmax] of the ray overlaps the box; tnear is the (conservative) entry distance,
// used to order children.
LS_FN bool ray_box(IN(vec3) origin, IN(vec3) inv_dir, float tmin, float tmax, IN(vec3) lo, IN(vec3) hi, OUT(float) tnear) {
  precise vec3 t0 = (lo - origin) * inv_dir;
  precise vec3 t1 = (hi - origin) * inv_dir;
  vec3 tn = min(t0, t1);
  vec3 tf = max(t0, t1);
  tnear = max(max(tn.x, tn.y), max(tn.z, tmin));
  float tfar = widen_distance(min(min(tf.x, tf.y), min(tf.z, tmax)));
  return tnear <= tfar;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
