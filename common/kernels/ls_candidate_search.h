// The Line Space candidate search (docs/design.md §3), a *context* file included after traverse_bvh.h.
//
// For a shaft of the LS node at BVH node `node`, ray 0 joins the centres of its start and end patches;
// if it misses, rays 1..further_rays join the sub-patch points of ls_search_offsets(k), in that order.
// Each is traced as the closed segment between its two points, closest hit, against the node's own
// subtree only and without any Line Space.  The first that hits gives the candidate (an index into
// tris[]); none hits: the shaft is empty (LS_INVALID).  N and 1 / N are the LS node's own (host-made).

// The search segment from a to b as a + t d, t in [0, 1]; false when it has no length (skipped).
LS_FN bool ls_segment(IN(vec3) a, IN(vec3) b, OUT(vec3) d) {
  precise vec3 ab = b - a;
  d = ab;
  return !(ab.x == 0.0f && ab.y == 0.0f && ab.z == 0.0f);
}

// The k-th search segment of a shaft, from a to a + d; false when it has no length (skipped).
LS_FN bool ls_search_segment(IN(LsNode) ls, uint shaft, uint k, OUT(vec3) a, OUT(vec3) d) {
  uint start_patch;
  uint end_patch;
  ls_shaft_patches(shaft, ls.n, start_patch, end_patch);
  vec4 s = ls_search_offsets(k);
  a = ls_patch_point(ls.lo, ls.hi, start_patch, ls.n, ls.inv_n, s.x, s.y);
  vec3 b = ls_patch_point(ls.lo, ls.hi, end_patch, ls.n, ls.inv_n, s.z, s.w);
  return ls_segment(a, b, d);
}

// The segment's hit to start from: t = 1 (its far end), no triangle.
LS_FN Hit ls_search_hit() {
  Hit hit;
  hit.t = 1.0f;
  hit.instance = LS_INVALID;
  hit.triangle = LS_INVALID;
  hit.u = 0.0f;
  hit.v = 0.0f;
  return hit;
}

LS_FN uint ls_find_candidate(uint node, IN(LsNode) ls, uint shaft, uint further_rays, uint instance) {
  for (uint k = 0u; k <= further_rays; ++k) {
    vec3 a;
    vec3 d;
    if (!ls_search_segment(ls, shaft, k, a, d)) continue;
    Hit hit = ls_search_hit();
    uint prim = LS_INVALID;
    trace_bvh(node, a, d, 0.0f, hit.t, instance, false, false, hit, prim);
    if (prim != LS_INVALID) return prim;
  }
  return LS_INVALID;
}
