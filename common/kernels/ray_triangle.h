// Watertight, division-free ray/triangle test.
//
// The vertices are translated to the ray's origin and scaled by one power of two (exact), then the
// three edge functions e_i = dot(d, cross(p_j, p_k)) are taken.  Each is an expression of its edge's
// two endpoints alone whose value flips sign exactly when the endpoints are swapped (products
// commute, x - y = -(y - x) in IEEE arithmetic), so two triangles sharing an edge see exactly opposite
// values: no ray slips between them, and a ray exactly on the edge (e = 0) hits both.  The hit/miss
// and [tmin, tmax] decisions use only +, -, * (correctly rounded everywhere, DESIGN §5); the one
// division computes t, u, v after the decision.  Both faces are hit.  A degenerate (zero-area)
// triangle, or a ray in the triangle's plane, is never hit.
#ifndef LS_RAY_TRIANGLE_H
#define LS_RAY_TRIANGLE_H

#include "float_bits.h"
#include "layouts.h"

#ifdef __cplusplus
namespace lsk {
#endif

// A ray prepared for triangle tests: its direction scaled by 2^dir_exp into [1, 2).
struct TriRay {
  vec3 origin;
  int dir_exp;
  vec3 dir;
  float pad;
};

LS_FN TriRay make_tri_ray(IN(vec3) origin, IN(vec3) dir) {
  TriRay r;
  r.origin = origin;
  r.dir_exp = unit_exponent(max_abs(dir));
  r.dir = scale_pow2(dir, r.dir_exp);
  r.pad = 0.0f;
  return r;
}

// True when the triangle is hit at a distance in [tmin, tmax] (in units of the unscaled direction);
// then t, u and v (weights of p1 and p2) are set.
LS_FN bool ray_triangle(IN(TriRay) r, float tmin, float tmax, IN(vec3) p0, IN(vec3) p1, IN(vec3) p2,
                        OUT(float) t, OUT(float) u, OUT(float) v) {
  precise vec3 a = p0 - r.origin;
  precise vec3 b = p1 - r.origin;
  precise vec3 c = p2 - r.origin;
  float m = max(max(max_abs(a), max_abs(b)), max_abs(c));
  if (m == 0.0f) return false;
  int ks = unit_exponent(m);
  a = scale_pow2(a, ks);
  b = scale_pow2(b, ks);
  c = scale_pow2(c, ks);
  // Edge functions in Pluecker form: cross(b + c, c - b) = 2 cross(b, c), but its products are
  // (distance x edge length) rather than (distance x distance), so the rounding error grows linearly,
  // not quadratically, with distance / triangle size (Embree's robust intersector does the same).
  // Swapping an edge's endpoints still negates the value exactly (b + c = c + b, c - b = -(b - c)):
  // watertight as before.
  precise float e0 = dot(r.dir, cross(b + c, c - b));
  precise float e1 = dot(r.dir, cross(c + a, a - c));
  precise float e2 = dot(r.dir, cross(a + b, b - a));
  if ((e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) && (e0 > 0.0f || e1 > 0.0f || e2 > 0.0f)) return false;
  precise float det = e0 + e1 + e2;
  if (det == 0.0f) return false;
  // t from the plane: n from the untranslated edges (exact to a few ulps of the edge), scaled by a
  // power of two; t' = dot(n, a) / dot(n, dir).
  precise vec3 f1 = p1 - p0;
  precise vec3 f2 = p2 - p0;
  int kf = unit_exponent(max(max_abs(f1), max_abs(f2)));
  f1 = scale_pow2(f1, kf);
  f2 = scale_pow2(f2, kf);
  precise vec3 n = cross(f1, f2);
  precise float T = dot(n, a);
  precise float D = dot(n, r.dir);
  if (D == 0.0f) return false;
  if (D < 0.0f) {
    T = -T;
    D = -D;
  }
  // t = t' * 2^(dir_exp - ks); compare T against the interval scaled the other way.
  precise float lo = scale_pow2(tmin, ks - r.dir_exp) * D;
  precise float hi = scale_pow2(tmax, ks - r.dir_exp) * D;
  if (!(T >= lo && T <= hi)) return false;
  t = clamp(scale_pow2(T / D, r.dir_exp - ks), tmin, tmax);
  u = e1 / det;
  v = e2 / det;
  return true;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
