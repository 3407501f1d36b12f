// Watertight ray/triangle test (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection",
// JCGT 2013) with the triangle's distance taken from its plane.
//
// The vertices are translated to the ray's origin and scaled by one power of two (exact; keeps
// products far from overflow at 1e20 and from underflow at 1e-20), then sheared so the ray runs along
// +z.  The edge functions U, V, W are 2-d orientations of the sheared vertices, which depend on each
// vertex and the ray alone, so neighbours sharing an edge or a vertex see the same numbers.  A
// non-zero float orientation has the right sign (rounding is monotonic); a zero one is recomputed in
// double, where the products of floats are exact, so every sign is exact and no ray slips through an
// edge or a vertex.  Ties (a ray exactly on an edge) hit both triangles; traversal breaks them by id.
//
// t = dot(n, p0 - o) / dot(n, d) with n from the triangle's own edges: accurate however far the
// triangle is.  The interval decision is made on that t, so the reported t always lies in
// [tmin, tmax].  Both faces are hit; a degenerate triangle or a ray in its plane never is.
#ifndef LS_RAY_TRIANGLE_H
#define LS_RAY_TRIANGLE_H

#include "float_bits.h"
#include "layouts.h"

#ifdef __cplusplus
namespace lsk {
#endif

// A ray prepared for triangle tests: the direction scaled by 2^dir_exp into [1, 2), the axes that
// make it +z, and the shear.
struct TriRay {
  vec3 origin;
  int dir_exp;
  vec3 dir;
  uint kx;
  uint ky;
  uint kz;
  float sx;
  float sy;
  float sz;
  float pad0;
  float pad1;
  float pad2;
};

LS_FN TriRay make_tri_ray(IN(vec3) origin, IN(vec3) dir) {
  TriRay r;
  r.origin = origin;
  r.dir_exp = unit_exponent(max_abs(dir));
  r.dir = scale_pow2(dir, r.dir_exp);
  vec3 ad = abs(r.dir);
  r.kz = ad.x >= ad.y ? (ad.x >= ad.z ? 0u : 2u) : (ad.y >= ad.z ? 1u : 2u);
  r.kx = (r.kz + 1u) % 3u;
  r.ky = (r.kx + 1u) % 3u;
  if (component(r.dir, r.kz) < 0.0f) {  // keep the winding: swap the other two axes
    uint k = r.kx;
    r.kx = r.ky;
    r.ky = k;
  }
  r.sx = component(r.dir, r.kx) / component(r.dir, r.kz);
  r.sy = component(r.dir, r.ky) / component(r.dir, r.kz);
  r.sz = 1.0f / component(r.dir, r.kz);
  r.pad0 = 0.0f;
  r.pad1 = 0.0f;
  r.pad2 = 0.0f;
  return r;
}

// The first half of the test: the triangle translated to the ray's origin, scaled and sheared, and
// its three edge functions.  The CPU's fast path computes the same values four triangles at a time
// and finishes the survivors with ray_triangle_plane (cpu/trace/triangle_blocks.h).
struct TriEdges {
  vec3 a;    // p0 - origin, scaled by 2^ks (the plane distance is taken from it)
  int ks;
  float eu;  // edge functions (signed 2-d orientations), exact in sign
  float ev;
  float ew;
  float pad;
};

// False when the triangle cannot be hit (its vertices coincide with the origin); else e is set.
LS_FN bool ray_triangle_edges(IN(TriRay) r, IN(vec3) p0, IN(vec3) p1, IN(vec3) p2, OUT(TriEdges) e) {
  precise vec3 a = p0 - r.origin;
  precise vec3 b = p1 - r.origin;
  precise vec3 c = p2 - r.origin;
  float m = max(max(max_abs(a), max_abs(b)), max_abs(c));
  e.a = vec3(0.0f);
  e.ks = 0;
  e.eu = 0.0f;
  e.ev = 0.0f;
  e.ew = 0.0f;
  e.pad = 0.0f;
  if (m == 0.0f) return false;
  int ks = unit_exponent(m);
  a = scale_pow2(a, ks);
  b = scale_pow2(b, ks);
  c = scale_pow2(c, ks);
  precise float ax = component(a, r.kx) - r.sx * component(a, r.kz);
  precise float ay = component(a, r.ky) - r.sy * component(a, r.kz);
  precise float bx = component(b, r.kx) - r.sx * component(b, r.kz);
  precise float by = component(b, r.ky) - r.sy * component(b, r.kz);
  precise float cx = component(c, r.kx) - r.sx * component(c, r.kz);
  precise float cy = component(c, r.ky) - r.sy * component(c, r.kz);
  precise float eu = cx * by - cy * bx;
  precise float ev = ax * cy - ay * cx;
  precise float ew = bx * ay - by * ax;
  if (eu == 0.0f || ev == 0.0f || ew == 0.0f) {
    precise double du = double(cx) * double(by) - double(cy) * double(bx);
    precise double dv = double(ax) * double(cy) - double(ay) * double(cx);
    precise double dw = double(bx) * double(ay) - double(by) * double(ax);
    eu = float(du);
    ev = float(dv);
    ew = float(dw);
  }
  e.a = a;
  e.ks = ks;
  e.eu = eu;
  e.ev = ev;
  e.ew = ew;
  return true;
}

// The normal of the triangle's plane: n from the untranslated edges, scaled by a power of two.  It
// depends on the triangle alone (the CPU's fast path keeps it per triangle).
LS_FN vec3 triangle_plane_normal(IN(vec3) p0, IN(vec3) p1, IN(vec3) p2) {
  precise vec3 f1 = p1 - p0;
  precise vec3 f2 = p2 - p0;
  int kf = unit_exponent(max(max_abs(f1), max_abs(f2)));
  f1 = scale_pow2(f1, kf);
  f2 = scale_pow2(f2, kf);
  precise vec3 n = cross(f1, f2);
  return n;
}

// The second half, given the plane's normal n: the signs of the edge functions, then the distance
// from the plane and the barycentric weights.
LS_FN bool ray_triangle_plane(IN(TriRay) r, float tmin, float tmax, IN(vec3) n, IN(TriEdges) e, OUT(float) t,
                              OUT(float) u, OUT(float) v) {
  if ((e.eu < 0.0f || e.ev < 0.0f || e.ew < 0.0f) && (e.eu > 0.0f || e.ev > 0.0f || e.ew > 0.0f)) return false;
  precise float det = e.eu + e.ev + e.ew;
  if (det == 0.0f) return false;
  precise float tn = dot_in_order(n, e.a);
  precise float td = dot_in_order(n, r.dir);
  if (td == 0.0f) return false;
  // dot(n, a) / dot(n, dir) is t scaled by 2^(ks - dir_exp); a t of -0 is reported as +0.
  precise float tt = positive_zero(scale_pow2(tn / td, r.dir_exp - e.ks));
  if (!(tt >= tmin && tt <= tmax)) return false;
  t = tt;
  u = e.ev / det;
  v = e.ew / det;
  return true;
}

// True when the triangle is hit at a distance in [tmin, tmax] (in units of the unscaled direction);
// then t, u and v (weights of p1 and p2) are set.
LS_FN bool ray_triangle(IN(TriRay) r, float tmin, float tmax, IN(vec3) p0, IN(vec3) p1, IN(vec3) p2,
                        OUT(float) t, OUT(float) u, OUT(float) v) {
  TriEdges e;
  if (!ray_triangle_edges(r, p0, p1, p2, e)) return false;
  return ray_triangle_plane(r, tmin, tmax, triangle_plane_normal(p0, p1, p2), e, t, u, v);
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
