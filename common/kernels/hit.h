// The running result of a closest-hit query, and the rule that makes it independent of the order
// in which a structure visits triangles: the smaller t wins, ties go to the lower (instance, triangle).
#ifndef LS_HIT_H
#define LS_HIT_H

#include "float_bits.h"
#include "layouts.h"

#ifdef __cplusplus
namespace lsk {
#endif

// Offers a triangle hit to the running result; true when it became the result.
LS_FN bool offer_hit(float t, float u, float v, uint instance, uint triangle, INOUT(Hit) hit) {
  // ray_triangle never returns t > hit.t, so "not closer" means "equal": then the lower id wins.
  if (t < hit.t || instance < hit.instance || (instance == hit.instance && triangle < hit.triangle)) {
    hit.t = t;
    hit.u = u;
    hit.v = v;
    hit.instance = instance;
    hit.triangle = triangle;
    return true;
  }
  return false;
}

LS_FN Hit empty_hit(IN(Ray) ray) {
  Hit hit;
  hit.t = ray.tmax;
  hit.instance = LS_INVALID;
  hit.triangle = LS_INVALID;
  hit.u = 0.0f;
  hit.v = 0.0f;
  return hit;
}

// A miss reports t = +inf (docs/design.md §9).
LS_FN Hit finish_hit(IN(Hit) hit) {
  Hit h = hit;
  if (h.triangle == LS_INVALID) h.t = ls_infinity();
  return h;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
