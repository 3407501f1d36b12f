// The Line Space candidate search (DESIGN §3), a *context* file included after traverse_bvh.h.
//
// For a shaft of the LS node at BVH node `node`, ray 0 joins the centres of its start and end patches;
// if it misses, rays 1..further_rays join the sub-patch points of ls_search_offsets(k), in that order.
// Each is traced as the closed segment between its two points, closest hit, against the node's own
// subtree only and without any Line Space.  The first that hits gives the candidate (an index into
// tris[]); none hits: the shaft is empty (LS_INVALID).  N and 1 / N are the LS node's own (host-made).
LS_FN uint ls_find_candidate(uint node, IN(LsNode) ls, uint shaft, uint further_rays, uint instance) {
  uint n = ls.n;
  float inv_n = ls.inv_n;
  uint start_patch;
  uint end_patch;
  ls_shaft_patches(shaft, n, start_patch, end_patch);
  for (uint k = 0u; k <= further_rays; ++k) {
    vec4 s = ls_search_offsets(k);
    vec3 a = ls_patch_point(ls.lo, ls.hi, start_patch, n, inv_n, s.x, s.y);
    vec3 b = ls_patch_point(ls.lo, ls.hi, end_patch, n, inv_n, s.z, s.w);
    precise vec3 d = b - a;
    if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) continue;
    Hit hit;
    hit.t = 1.0f;
    hit.instance = LS_INVALID;
    hit.triangle = LS_INVALID;
    hit.u = 0.0f;
    hit.v = 0.0f;
    uint prim = LS_INVALID;
    trace_bvh(node, a, d, 0.0f, instance, false, false, hit, prim);
    if (prim != LS_INVALID) return prim;
  }
  return LS_INVALID;
}
