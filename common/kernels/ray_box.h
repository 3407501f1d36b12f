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

// t pushed outwards by a relative 2^-12 of its magnitude.  2*gamma(3) (about 3.6e-7) bounds the
// error of a slab distance (Ize 2013); the much larger slack also covers the triangle test's t, so
// that a box holding a hit as close as the current one is not pruned.  That t, taken from the
// triangle's plane, errs by tens of ulps in general, and by over a hundred where a ray passes through
// a vertex shared by triangles of different planes (measured on an icosphere, where 2^-18 let the
// visiting order decide between two triangles at the same vertex).  The pruning is then, for every
// ray but ones grazing a plane, independent of the order, and so is the closest hit.
LS_CONST float LS_WIDEN_SLACK = 2.44140625e-4f;  // 2^-12

LS_FN float widen_distance(float t) {
  precise float w = t + abs(t) * LS_WIDEN_SLACK;
  return w;
}

// The distances at which the ray enters and leaves one slab [lo, hi] of a closed box.  A zero (or
// denormal) direction component, marked by safe_reciprocal's huge value, means the ray runs parallel
// to the slab: inside it (its planes included) for all t, or never.
LS_FN void slab_interval(float origin, float inv_dir, float lo, float hi, OUT(float) t_enter, OUT(float) t_leave) {
  LS_CONST float big = 3.0e38f;
  if (abs(inv_dir) == big) {
    bool inside = origin >= lo && origin <= hi;
    t_enter = inside ? -big : big;
    t_leave = inside ? big : -big;
    return;
  }
  precise float t0 = (lo - origin) * inv_dir;
  precise float t1 = (hi - origin) * inv_dir;
  t_enter = min(t0, t1);
  t_leave = max(t0, t1);
}

// True when [tmin, tmax] of the ray overlaps the box; tnear is the (conservative) entry distance,
// used to order children.
LS_FN bool ray_box(IN(vec3) origin, IN(vec3) inv_dir, float tmin, float tmax, IN(vec3) lo, IN(vec3) hi, OUT(float) tnear) {
  vec3 tn;
  vec3 tf;
  slab_interval(origin.x, inv_dir.x, lo.x, hi.x, tn.x, tf.x);
  slab_interval(origin.y, inv_dir.y, lo.y, hi.y, tn.y, tf.y);
  slab_interval(origin.z, inv_dir.z, lo.z, hi.z, tn.z, tf.z);
  tnear = max(max(tn.x, tn.y), max(tn.z, tmin));
  float tfar = widen_distance(min(min(tf.x, tf.y), min(tf.z, tmax)));
  return tnear <= tfar;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
