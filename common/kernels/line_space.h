// Line Space geometry (docs/design.md §3): patches, shafts, and the shaft a line falls in.
//
// Enumeration, fixed for every back end:
//  - faces 0..5 are -X, +X, -Y, +Y, -Z, +Z: axis = face / 2, side = face % 2 (0 = lo, 1 = hi);
//  - on a face of axis a the patch axes are u = (a + 1) % 3 and v = (a + 2) % 3, each cut into N
//    equal parts; patch (i, j) covers [i, i+1)/N along u and [j, j+1)/N along v;
//  - patch index = face * N^2 + j * N + i, in [0, 6 N^2);
//  - a shaft is an ordered (start patch, end patch) pair on different faces.  Its index is
//    start * 5 N^2 + e', where e' numbers the end patch among the 5 N^2 patches not on the start
//    face (the patches of the faces after the start face move down by N^2): 30 N^4 shafts per LS.
#ifndef LS_LINE_SPACE_H
#define LS_LINE_SPACE_H

#include "float_bits.h"
#include "layouts.h"
#include "ray_box.h"

#ifdef __cplusplus
namespace lsk {
#endif

LS_FN uint ls_shaft_count(uint n) { return 30u * n * n * n * n; }

LS_FN uint ls_patch_index(uint face, uint i, uint j, uint n) { return face * n * n + j * n + i; }

// The shaft of two patches whose faces are known: no division.
LS_FN uint ls_shaft_index_on_faces(uint start_patch, uint start_face, uint end_patch, uint end_face, uint n) {
  uint nn = n * n;
  uint end_rank = end_face > start_face ? end_patch - nn : end_patch;
  return start_patch * 5u * nn + end_rank;
}

LS_FN uint ls_shaft_index(uint start_patch, uint end_patch, uint n) {
  uint nn = n * n;
  return ls_shaft_index_on_faces(start_patch, start_patch / nn, end_patch, end_patch / nn, n);
}

LS_FN void ls_shaft_patches(uint shaft, uint n, OUT(uint) start_patch, OUT(uint) end_patch) {
  uint nn = n * n;
  start_patch = shaft / (5u * nn);
  uint end_rank = shaft - start_patch * 5u * nn;
  uint start_face = start_patch / nn;
  end_patch = end_rank / nn >= start_face ? end_rank + nn : end_rank;
}

// The shaft of the same patches the other way round (end patch to start patch).
LS_FN uint ls_reverse_shaft(uint shaft, uint n) {
  uint start_patch;
  uint end_patch;
  ls_shaft_patches(shaft, n, start_patch, end_patch);
  return ls_shaft_index(end_patch, start_patch, n);
}

// The point at (i + su, j + sv) / N on a patch of the box [lo, hi]; inv_n = 1 / N, computed once by
// the host so that no device divides.
LS_FN vec3 ls_patch_point(IN(vec3) lo, IN(vec3) hi, uint patch_id, uint n, float inv_n, float su, float sv) {
  uint nn = n * n;
  uint face = patch_id / nn;
  uint rest = patch_id - face * nn;
  uint j = rest / n;
  uint i = rest - j * n;
  uint a = face / 2u;
  uint ua = a == 2u ? 0u : a + 1u;  // the face's other two axes in cyclic order
  uint va = a == 0u ? 2u : a - 1u;
  precise float fu = (float(i) + su) * inv_n;
  precise float fv = (float(j) + sv) * inv_n;
  vec3 p;
  p[a] = (face % 2u) == 0u ? lo[a] : hi[a];
  precise float pu = lo[ua] + (hi[ua] - lo[ua]) * fu;
  precise float pv = lo[va] + (hi[va] - lo[va]) * fv;
  p[ua] = pu;
  p[va] = pv;
  return p;
}

// Sub-patch offsets of the candidate search: ray 0 joins the patch centres; ray k >= 1 joins the
// points fract(0.5 + k * alpha) of the 4-d Kronecker (R4) sequence, alpha_i = phi4^-i with phi4 the
// real root of x^5 = x + 1: (start u, start v, end u, end v).
LS_FN vec4 ls_search_offsets(uint k) {
  vec4 alpha = vec4(0.85667488f, 0.73389185f, 0.62870672f, 0.53859726f);
  precise vec4 x = vec4(0.5f) + float(k) * alpha;
  return x - floor(x);
}

// The patch a point on a face falls in; scale = N / extent per axis (host-computed).
LS_FN uint ls_patch_of_point(IN(vec3) p, IN(vec3) lo, IN(vec3) scale, uint face, uint n) {
  uint a = face / 2u;
  uint ua = a == 2u ? 0u : a + 1u;  // the face's other two axes in cyclic order
  uint va = a == 0u ? 2u : a - 1u;
  int last = int(n) - 1;
  // int() truncates toward zero where floor() would round down, which differs only on (-1, 0),
  // where both clamp to 0: the same patch without the floor (a dozen instructions on SSE2).
  int i = clamp(int((p[ua] - lo[ua]) * scale[ua]), 0, last);
  int j = clamp(int((p[va] - lo[va]) * scale[va]), 0, last);
  return ls_patch_index(face, uint(i), uint(j), n);
}

// Where the ray's line enters and leaves the box [lo, hi] (the line, not the ray: the entry may lie
// behind the origin).  Ties between slabs (edges, corners) go to the lowest axis.  False when the
// line misses the box or enters and leaves through the same face (a line along a face): no shaft.
LS_FN bool ls_line_shaft(IN(vec3) origin, IN(vec3) dir, IN(vec3) inv_dir, IN(vec3) lo, IN(vec3) hi, IN(vec3) scale,
                         uint n, OUT(uint) shaft, OUT(float) t_in, OUT(float) t_out) {
  vec3 tn;
  vec3 tf;
  slab_interval(origin.x, inv_dir.x, lo.x, hi.x, tn.x, tf.x);
  slab_interval(origin.y, inv_dir.y, lo.y, hi.y, tn.y, tf.y);
  slab_interval(origin.z, inv_dir.z, lo.z, hi.z, tn.z, tf.z);
  uint in_axis = 0u;
  t_in = tn.x;
  if (tn.y > t_in) { in_axis = 1u; t_in = tn.y; }
  if (tn.z > t_in) { in_axis = 2u; t_in = tn.z; }
  uint out_axis = 0u;
  t_out = tf.x;
  if (tf.y < t_out) { out_axis = 1u; t_out = tf.y; }
  if (tf.z < t_out) { out_axis = 2u; t_out = tf.z; }
  shaft = LS_INVALID;
  if (!(t_in <= t_out)) return false;
  // Entering through the lo side when moving up the axis; leaving through the hi side.
  uint in_face = in_axis * 2u + (dir[in_axis] > 0.0f ? 0u : 1u);
  uint out_face = out_axis * 2u + (dir[out_axis] > 0.0f ? 1u : 0u);
  if (in_face == out_face) return false;
  precise vec3 p_in = origin + dir * t_in;
  precise vec3 p_out = origin + dir * t_out;
  uint start_patch = ls_patch_of_point(p_in, lo, scale, in_face, n);
  uint end_patch = ls_patch_of_point(p_out, lo, scale, out_face, n);
  shaft = ls_shaft_index_on_faces(start_patch, in_face, end_patch, out_face, n);
  return true;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
