// The Line Space lookup during traversal (docs/design.md §3), a *context* file like traverse_bvh.h: it reads
//   ls_nodes[] LsNode, ls_candidates[] uint, ls_records[] LsRecord (a candidate's plane, barycentric
//   rows, vertex normals and id), tri_instances[], the parameters ls_cos2 (cos^2 of the refusal angle;
//   negative: refuse everything, empty shafts included), ls_behind (LS_BEHIND_*: --ls-behind, below)
//   and ls_leave_reach (--ls-leave-reach, below), and the counters ls_counters.  N is the LS node's
//   own (LsNode.n).
//
// A lookup's answer is a function of the ray and the node alone, never of the hit found so far, so
// the closest hit is the same in any visiting order (order-free answers, docs/design.md §3):
//  - accepted: the candidate's plane hit, when it lies in the node's *window*, the part of
//    [tmin, tmax as launched] inside the node's own BVH box (the slab interval that box's pruning
//    computes, widened by LS_ACCEPT_SLACK).  It is offered to the running hit like a triangle's;
//  - empty: no hit in the subtree;
//  - refused: the exact closest hit of the subtree, which the caller traverses.
// The shaft comes from where the ray's *line* enters and leaves the LS box, so an origin inside the
// box still finds its shaft.  A candidate is used as an infinite plane: refused when the ray is
// parallel to the plane, when the plane hit lies outside the window (before the box or tmin, past
// the box or tmax), when the line runs along a face of the box (no shaft), or when the angle between
// the ray and the candidate's vertex normals extrapolated to the plane hit exceeds the refusal angle.
// With --ls-behind exact or empty, a ray whose line enters the LS box before tmin (an origin inside
// it) is never answered by the shaft's first candidate: only "empty" (exact: an empty shaft; empty:
// below) answers it, and the rest is refused as behind.
//
// --ls-behind reverse (LS_BEHIND_REVERSE): a plane hit behind the origin (before tmin) is not refused.  The
// shaft's candidate is the first surface its line meets from the start patch; the *reverse* shaft's
// (end patch to start patch, stored anyway) is the last, the one a ray from inside the box meets
// going on.  So the reverse shaft's candidate answers instead, as an infinite plane like the first.
// Its plane hit within half a patch (half the line's chord through the box over N) of tmin, or
// behind it, is the surface the ray leaves; past the line's exit from the box it is no surface in
// the box: either way the shaft holds nothing ahead of the ray (empty, no hit in the subtree), and
// so does an empty reverse shaft.  Otherwise outside the window, parallel or past the angle: refused.
//
// --ls-behind empty (LS_BEHIND_EMPTY): the reverse shaft answers only "empty", and only where it is
// empty or its plane hit lies within half a patch of tmin, either side, and on the candidate
// triangle or within ls_leave_reach patches outside it; otherwise (a candidate ahead, farther
// behind, past the exit, off its triangle, or refused) the lookup is refused as behind.  Its speed
// and error beside the other modes, and how the reach was chosen: docs/performance.md.

LS_CONST uint LS_BEHIND_EXACT = 0u;
LS_CONST uint LS_BEHIND_REVERSE = 1u;
LS_CONST uint LS_BEHIND_EMPTY = 2u;

// The relative slack of a lookup's window: without it, a flat box's window is a single rounded t,
// and a quarter of its lookups were refused by rounding.  Below widen_distance's 2^-12, so that a
// box the walk prunes (its entry beyond the widened current t) never holds an answer that would win.
LS_CONST float LS_ACCEPT_SLACK = 1.220703125e-4f;  // 2^-13

LS_CONST uint LS_FALLBACK = 0u;
LS_CONST uint LS_EMPTY = 1u;
LS_CONST uint LS_ACCEPTED = 2u;

// Octahedral unit-vector decoding (Cigolle et al., JCGT 2014).
LS_FN vec3 ls_decode_normal(uint packed) {
  vec2 e = unpackSnorm2x16(packed);
  vec3 v = vec3(e.x, e.y, 1.0f - abs(e.x) - abs(e.y));
  if (v.z < 0.0f) {
    float x = (1.0f - abs(e.y)) * (e.x >= 0.0f ? 1.0f : -1.0f);
    float y = (1.0f - abs(e.x)) * (e.y >= 0.0f ? 1.0f : -1.0f);
    v.x = x;
    v.y = y;
  }
  return normalize(v);
}

// A word of ls_candidates[] holds 4 / bytes candidates (bytes = 1, 2 or 4): log2 of that count.
LS_FN uint ls_per_word_log2(IN(LsNode) ls) { return 2u - (ls.bytes >> 1u); }

// The word of ls_candidates[] that holds a shaft's candidate.
LS_FN uint ls_candidate_word(IN(LsNode) ls, uint shaft) { return ls.candidates + (shaft >> ls_per_word_log2(ls)); }

// The candidate of a shaft as an index into tris[], or LS_INVALID for an empty shaft (shifts, not
// divisions).
LS_FN uint ls_candidate(IN(LsNode) ls, uint shaft) {
  uint per_word_log2 = ls_per_word_log2(ls);
  uint word = ls_candidates[ls_candidate_word(ls, shaft)];
  if (ls.bytes == 4u) return word == LS_INVALID ? LS_INVALID : ls.range_first + word;
  uint bits = ls.bytes * 8u;
  uint mask = (1u << bits) - 1u;
  uint local = (word >> ((shaft & ((1u << per_word_log2) - 1u)) * bits)) & mask;
  return local == mask ? LS_INVALID : ls.range_first + local;
}

// What ls_plane_hit found: the plane hit is usable, or why not.
LS_CONST uint LS_PLANE_HIT = 0u;
LS_CONST uint LS_PLANE_PARALLEL = 1u;
LS_CONST uint LS_PLANE_BEHIND = 2u;
LS_CONST uint LS_PLANE_BEYOND = 3u;
LS_CONST uint LS_PLANE_ANGLE = 4u;

// Barycentric coordinates b1, b2 of the point at t on the ray in the plane of `rec` (b0 = 1 - b1 - b2),
// outside [0, 1] when it lies off the triangle.
LS_FN void ls_plane_barycentrics(IN(LsRecord) rec, IN(vec3) origin, IN(vec3) dir, float t, OUT(float) b1, OUT(float) b2) {
  precise vec3 q = origin + dir * t - rec.p0;
  b1 = dot_in_order(q, rec.b1);
  b2 = dot_in_order(q, rec.b2);
}

// Whether a barycentric weight b lies on its side of the edge, or at most sqrt(reach2) outside: b
// falls by |grad| a unit of distance.  NaN is outside.
LS_FN bool ls_within_edge(float b, IN(vec3) grad, float reach2) {
  precise float b_squared = b * b;
  precise float limit = reach2 * dot_in_order(grad, grad);
  return b >= 0.0f || b_squared <= limit;
}

// Whether the point at t on the ray, in the plane of ls_records[prim], lies on its triangle or at
// most `reach` (a t distance) outside the line of each edge; the rows b1, b2 are the gradients of
// their weights, and b0's is minus their sum.
LS_FN bool ls_plane_point_near_triangle(uint prim, IN(vec3) origin, IN(vec3) dir, float t, float reach) {
  LsRecord rec = ls_records[prim];
  float b1;
  float b2;
  ls_plane_barycentrics(rec, origin, dir, t, b1, b2);
  precise float b0 = 1.0f - b1 - b2;
  precise vec3 g0 = -(rec.b1 + rec.b2);
  precise float reach2 = reach * reach * dot_in_order(dir, dir);
  return ls_within_edge(b0, g0, reach2) && ls_within_edge(b1, rec.b1, reach2) && ls_within_edge(b2, rec.b2, reach2);
}

// The candidate ls_records[prim] as an infinite plane: its hit t in [tmin, tmax] and the
// barycentrics there, and the refusal angle's test on the vertex normals extrapolated to it.
LS_FN uint ls_plane_hit(uint prim, IN(vec3) origin, IN(vec3) dir, float tmin, float tmax, OUT(float) t_hit, OUT(float) u_hit,
                        OUT(float) v_hit) {
  t_hit = 0.0f;
  u_hit = 0.0f;
  v_hit = 0.0f;
  LsRecord rec = ls_records[prim];
  precise float denom = dot_in_order(dir, rec.n);
  if (denom == 0.0f) return LS_PLANE_PARALLEL;  // parallel, or a degenerate triangle (n = 0)
  precise float t = dot_in_order(rec.p0 - origin, rec.n) / denom;
  t_hit = t;
  if (!(t >= tmin)) return LS_PLANE_BEHIND;
  if (!(t <= tmax)) return LS_PLANE_BEYOND;
  float b1;
  float b2;
  ls_plane_barycentrics(rec, origin, dir, t, b1, b2);
  precise float b0 = 1.0f - b1 - b2;
  u_hit = b1;
  v_hit = b2;
  precise vec3 ne = ls_decode_normal(rec.normal0) * b0 + ls_decode_normal(rec.normal1) * b1 + ls_decode_normal(rec.normal2) * b2;
  precise float c = dot_in_order(dir, ne);
  precise float ne2 = dot_in_order(ne, ne);
  precise float lhs = c * c;
  precise float rhs = ls_cos2 * dot_in_order(dir, dir) * ne2;
  if (ne2 == 0.0f || lhs < rhs) return LS_PLANE_ANGLE;
  return LS_PLANE_HIT;
}

// The window of a lookup at the node whose BVH box is [box_lo, box_hi]: [window_lo, window_hi].
LS_FN void ls_window(IN(vec3) origin, IN(vec3) inv_dir, IN(vec3) box_lo, IN(vec3) box_hi, float tmin, float tmax,
                     OUT(float) window_lo, OUT(float) window_hi) {
  vec3 tn;
  vec3 tf;
  slab_interval(origin.x, inv_dir.x, box_lo.x, box_hi.x, tn.x, tf.x);
  slab_interval(origin.y, inv_dir.y, box_lo.y, box_hi.y, tn.y, tf.y);
  slab_interval(origin.z, inv_dir.z, box_lo.z, box_hi.z, tn.z, tf.z);
  float enter = max(max(tn.x, tn.y), tn.z);
  float leave = min(min(tf.x, tf.y), tf.z);
  precise float lo = enter - abs(enter) * LS_ACCEPT_SLACK;
  precise float hi = leave + abs(leave) * LS_ACCEPT_SLACK;
  window_lo = max(lo, tmin);
  window_hi = min(hi, tmax);
}

// Whether a lookup whose line enters the LS box at t_in reads its first candidate's record: not in
// exact mode from inside the box (t_in before tmin), where only an empty shaft answers
// (ls_shaft_lookup; a caller that prefetches the record asks the same).
LS_FN bool ls_reads_first_record(float t_in, float tmin) { return ls_behind != LS_BEHIND_EXACT || !(t_in < tmin); }

// ls_lookup once the ray's line is known to cross shaft `shaft` of `ls`, entering and leaving the
// LS box at t_in and t_out (ls_line_shaft), and its candidate `prim` is read (ls_candidate): what a
// caller that loads the shaft ahead of time runs.
LS_FN uint ls_shaft_lookup(IN(LsNode) ls, uint shaft, uint prim, float t_in, float t_out, IN(vec3) box_lo, IN(vec3) box_hi,
                           IN(vec3) origin, IN(vec3) dir, IN(vec3) inv_dir, float tmin, float tmax, uint instance,
                           INOUT(Hit) hit, INOUT(uint) hit_prim) {
  ls_counters.lookups += 1u;
  if (prim == LS_INVALID) {
    ls_counters.empty += 1u;
    return LS_EMPTY;
  }
  // The line enters the LS box before tmin (an origin inside it): the shaft's first surface, met from
  // its start patch, is rarely one ahead of the ray.  It lies behind, or its plane is crossed just
  // ahead by a ray that leaves a neighbouring facet of a curved surface (a false hit at once).  So
  // from inside, exact answers only an empty shaft and reads no record; empty asks the reverse shaft
  // as below when the plane hit is behind, and refuses the rest (docs/performance.md).
  if (!ls_reads_first_record(t_in, tmin)) {
    ls_counters.refused_behind += 1u;
    return LS_FALLBACK;
  }
  float window_lo;
  float window_hi;
  ls_window(origin, inv_dir, box_lo, box_hi, tmin, tmax, window_lo, window_hi);
  float t;
  float u;
  float v;
  uint found = ls_plane_hit(prim, origin, dir, window_lo, window_hi, t, u, v);
  if (ls_behind == LS_BEHIND_EMPTY && t_in < tmin && found == LS_PLANE_HIT) found = LS_PLANE_BEHIND;
  if (found == LS_PLANE_BEHIND && ls_behind != LS_BEHIND_EXACT && t < tmin) {
    prim = ls_candidate(ls, ls_reverse_shaft(shaft, ls.n));
    precise float half_patch = 0.5f * ls.inv_n * (t_out - t_in);
    precise float ahead = tmin + half_patch;
    if (prim != LS_INVALID) found = ls_plane_hit(prim, origin, dir, ahead, window_hi, t, u, v);
    // In empty mode only the surface the ray leaves (a plane hit within half a patch of tmin, on the
    // triangle or within ls_leave_reach patches of it) and an empty reverse shaft say "nothing ahead":
    // a last surface farther behind, past the box's exit or off its triangle (another surface of its
    // plane, with something standing between) is one the ray's line does not meet where the shaft's
    // does, and carried rays past a close true hit (docs/performance.md).
    precise float near_behind = tmin - half_patch;
    bool leaves = prim != LS_INVALID && found == LS_PLANE_BEHIND &&
                  (ls_behind != LS_BEHIND_EMPTY ||
                   (t >= near_behind && ls_plane_point_near_triangle(prim, origin, dir, t, 2.0f * ls_leave_reach * half_patch)));
    bool past_exit = ls_behind != LS_BEHIND_EMPTY && found != LS_PLANE_PARALLEL && t > t_out;
    if (prim == LS_INVALID || leaves || past_exit) {
      ls_counters.empty += 1u;
      return LS_EMPTY;
    }
    // Ahead of the origin but before the node's box (an origin outside it): refused like the first;
    // and every answer but "empty" in empty mode.
    if (ls_behind == LS_BEHIND_EMPTY || (found == LS_PLANE_HIT && t < window_lo)) found = LS_PLANE_BEHIND;
  }
  if (found == LS_PLANE_PARALLEL) {
    ls_counters.refused_parallel += 1u;
    return LS_FALLBACK;
  }
  if (found == LS_PLANE_BEHIND) {
    ls_counters.refused_behind += 1u;
    return LS_FALLBACK;
  }
  if (found == LS_PLANE_BEYOND) {
    ls_counters.refused_beyond += 1u;
    return LS_FALLBACK;
  }
  if (found == LS_PLANE_ANGLE) {
    ls_counters.refused_angle += 1u;
    return LS_FALLBACK;
  }
  // Only a hit as close as the current one meets the tie rule: offer_hit assumes t <= hit.t.
  uint inst = instance == LS_INVALID ? tri_instances[prim] : instance;
  if (t <= hit.t && offer_hit(t, u, v, inst, ls_records[prim].id, hit)) hit_prim = prim;
  ls_counters.accepted += 1u;
  return LS_ACCEPTED;
}

// One lookup at an LS node whose BVH box is [box_lo, box_hi], for a ray launched with [tmin, tmax]:
// LS_ACCEPTED (its plane hit offered to the running hit), LS_EMPTY (skip the subtree) or
// LS_FALLBACK (traverse the subtree exactly).
LS_FN uint ls_lookup(uint ls_index, IN(vec3) box_lo, IN(vec3) box_hi, IN(vec3) origin, IN(vec3) dir, IN(vec3) inv_dir,
                     float tmin, float tmax, uint instance, INOUT(Hit) hit, INOUT(uint) hit_prim) {
  LsNode ls = ls_nodes[ls_index];
  // A refusal angle of 0 refuses every approximation, the "no hit" of an empty shaft included, so
  // the structure answers exactly like its BVH.
  if (ls_cos2 < 0.0f) {
    ls_counters.lookups += 1u;
    ls_counters.refused_angle += 1u;
    return LS_FALLBACK;
  }
  uint shaft;
  float t_in;
  float t_out;
  if (!ls_line_shaft(origin, dir, inv_dir, ls.lo, ls.hi, ls.scale, ls.n, shaft, t_in, t_out)) {
    ls_counters.lookups += 1u;
    ls_counters.refused_no_shaft += 1u;
    return LS_FALLBACK;
  }
  return ls_shaft_lookup(ls, shaft, ls_candidate(ls, shaft), t_in, t_out, box_lo, box_hi, origin, dir, inv_dir, tmin, tmax,
                         instance, hit, hit_prim);
}
