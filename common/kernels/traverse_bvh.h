// Exact closest-hit and any-hit traversal of the flat and two-level BVHs.
//
// A *context* file: it includes nothing and opens no namespace, because it is included where the
// scene's buffers are in scope — in a shader after the buffer declarations, in C++ inside the struct
// lsk::TraceContext (common/structure/trace_context.h) whose pointer members carry the same names:
//   nodes[]          BvhNode   every object BVH (2L) or the one flat BVH (F), children adjacent
//   tris[]           Triangle  in BVH order
//   tri_ids[]        uint      triangle id within its mesh, per triangle in BVH order
//   tri_instances[]  uint      instance id per triangle (flat structures only)
//   top_nodes[]      BvhNode   the top-level BVH over instances (2L only); leaves index instances[]
//   instances[]      InstanceRecord, in top-level BVH order (2L only)
//   node_ls[]        uint      LS node of each BVH node, or LS_INVALID (LS structures only)
//   ls_enabled       uint      non-zero: use the Line Space (see ls_lookup.h for the rest)
//   walk_far_first   uint      non-zero: visit the farther child first (tests: the answers must not
//                              depend on the order); a shader's is 0
//   count_work(node, boxes, triangles)  counts the box and triangle tests made at nodes[node]
//                    (LS_INVALID: at no object node, e.g. the top level): C++ sums them into a
//                    TraceWork, split at the Line Space nodes; a shader's is empty
// Ties at equal t go to the lower (instance, triangle), so the answer does not depend on the order in
// which the structure visits triangles.

LS_CONST int LS_STACK_SIZE = 64;  // the builder caps BVH depth below this

// Tests the triangles [first, first + count) of a leaf (the caller counts them: count_work).  Returns
// true when any_hit is set and a hit was found (the caller stops).
LS_FN bool trace_leaf(uint first, uint count, IN(TriRay) tri_ray, float tmin, uint instance, bool any_hit,
                      INOUT(Hit) hit, INOUT(uint) hit_prim) {
  for (uint i = first; i < first + count; ++i) {
    Triangle tri = tris[i];
    float t;
    float u;
    float v;
    if (ray_triangle(tri_ray, tmin, hit.t, vec3(tri.v0), vec3(tri.v1), vec3(tri.v2), t, u, v)) {
      uint inst = instance == LS_INVALID ? tri_instances[i] : instance;
      if (offer_hit(t, u, v, inst, tri_ids[i], hit)) {
        hit_prim = i;
        if (any_hit) return true;
      }
    }
  }
  return false;
}

// The ray carried into an instance's object space; an affine map keeps t unchanged.
LS_FN void instance_ray(IN(InstanceRecord) rec, IN(vec3) origin, IN(vec3) dir, OUT(vec3) object_origin,
                        OUT(vec3) object_dir) {
  // Sums spelled out in one order (dot_in_order): CPU and GPU must carry the ray identically.
  precise vec3 o = vec3(dot_in_order(vec3(rec.world_to_object0), origin) + rec.world_to_object0.w,
                        dot_in_order(vec3(rec.world_to_object1), origin) + rec.world_to_object1.w,
                        dot_in_order(vec3(rec.world_to_object2), origin) + rec.world_to_object2.w);
  precise vec3 d = vec3(dot_in_order(vec3(rec.world_to_object0), dir),
                        dot_in_order(vec3(rec.world_to_object1), dir),
                        dot_in_order(vec3(rec.world_to_object2), dir));
  object_origin = o;
  object_dir = d;
}

// Traverses the BVH rooted at nodes[root] with a ray given in that BVH's space, launched with
// [tmin, tmax] (hit.t may be smaller already: another instance's hit).  instance is the id to report,
// or LS_INVALID to read it per triangle (flat structures).  With use_ls, a node that carries a Line
// Space is answered by its lookup, and traversed exactly only when the lookup refuses.  hit_prim
// receives the tris[] index of the hit.  Returns true when any_hit is set and a hit was found (the
// caller stops).
LS_FN bool trace_bvh(uint root, IN(vec3) origin, IN(vec3) dir, float tmin, float tmax, uint instance, bool any_hit,
                     bool use_ls, INOUT(Hit) hit, INOUT(uint) hit_prim) {
  TriRay tri_ray = make_tri_ray(origin, dir);
  vec3 inv_dir = safe_reciprocal(dir);
  uint stack_node[LS_STACK_SIZE];
  float stack_t[LS_STACK_SIZE];
  int sp = 0;
  float t_root;
  count_work(LS_INVALID, 1u, 0u);  // the root's box: the walk's entry, never below a Line Space node
  if (!ray_box(origin, inv_dir, tmin, hit.t, nodes[root].lo, nodes[root].hi, t_root)) return false;
  uint current = root;
  while (true) {
    BvhNode node = nodes[current];
    bool descend = true;
    if (use_ls && node_ls[current] != LS_INVALID) {
      uint answer = ls_lookup(node_ls[current], node.lo, node.hi, origin, dir, inv_dir, tmin, tmax, instance, hit, hit_prim);
      if (answer == LS_ACCEPTED && any_hit) return true;
      descend = answer == LS_FALLBACK;
    }
    if (!descend) {
      // answered by the Line Space: continue with the stack
    } else if (node.count > 0u) {
      count_work(current, 0u, node.count);
      if (trace_leaf(node.first, node.count, tri_ray, tmin, instance, any_hit, hit, hit_prim)) return true;
    } else {
      uint left = node.first;
      uint right = node.first + 1u;
      float t_left;
      float t_right;
      count_work(current, 2u, 0u);
      bool hit_left = ray_box(origin, inv_dir, tmin, hit.t, nodes[left].lo, nodes[left].hi, t_left);
      bool hit_right = ray_box(origin, inv_dir, tmin, hit.t, nodes[right].lo, nodes[right].hi, t_right);
      if (hit_left && hit_right) {
        bool left_first = (t_left <= t_right) != (walk_far_first != 0u);
        stack_node[sp] = left_first ? right : left;
        stack_t[sp] = left_first ? t_right : t_left;
        sp = sp + 1;
        current = left_first ? left : right;
        continue;
      }
      if (hit_left || hit_right) {
        current = hit_left ? left : right;
        continue;
      }
    }
    // Pop the nearest pending node that can still hold something closer than the current hit.
    bool found = false;
    while (sp > 0 && !found) {
      sp = sp - 1;
      if (stack_t[sp] <= widen_distance(hit.t)) {
        current = stack_node[sp];
        found = true;
      }
    }
    if (!found) break;
  }
  return false;
}

LS_FN Hit trace_flat(IN(Ray) ray, bool any_hit) {
  Hit hit = empty_hit(ray);
  uint prim = LS_INVALID;
  trace_bvh(0u, ray.origin, ray.dir, ray.tmin, ray.tmax, LS_INVALID, any_hit, ls_enabled != 0u, hit, prim);
  return finish_hit(hit);
}

// The ray is carried into each instance's object space (instance_ray).
LS_FN Hit trace_two_level(IN(Ray) ray, bool any_hit) {
  Hit hit = empty_hit(ray);
  uint prim = LS_INVALID;
  vec3 inv_dir = safe_reciprocal(ray.dir);
  uint stack_node[LS_STACK_SIZE];
  float stack_t[LS_STACK_SIZE];
  int sp = 0;
  float t_root;
  count_work(LS_INVALID, 1u, 0u);
  bool pending = ray_box(ray.origin, inv_dir, ray.tmin, hit.t, top_nodes[0].lo, top_nodes[0].hi, t_root);
  uint current = 0u;
  while (pending) {
    BvhNode node = top_nodes[current];
    if (node.count > 0u) {
      for (uint i = node.first; i < node.first + node.count; ++i) {
        InstanceRecord rec = instances[i];
        vec3 o;
        vec3 d;
        instance_ray(rec, ray.origin, ray.dir, o, d);
        if (trace_bvh(rec.root, o, d, ray.tmin, ray.tmax, rec.instance, any_hit, ls_enabled != 0u, hit, prim))
          return finish_hit(hit);
      }
    } else {
      uint left = node.first;
      uint right = node.first + 1u;
      float t_left;
      float t_right;
      count_work(LS_INVALID, 2u, 0u);
      bool hit_left = ray_box(ray.origin, inv_dir, ray.tmin, hit.t, top_nodes[left].lo, top_nodes[left].hi, t_left);
      bool hit_right = ray_box(ray.origin, inv_dir, ray.tmin, hit.t, top_nodes[right].lo, top_nodes[right].hi, t_right);
      if (hit_left && hit_right) {
        bool left_first = t_left <= t_right;
        stack_node[sp] = left_first ? right : left;
        stack_t[sp] = left_first ? t_right : t_left;
        sp = sp + 1;
        current = left_first ? left : right;
        continue;
      }
      if (hit_left || hit_right) {
        current = hit_left ? left : right;
        continue;
      }
    }
    pending = false;
    while (sp > 0 && !pending) {
      sp = sp - 1;
      if (stack_t[sp] <= widen_distance(hit.t)) {
        current = stack_node[sp];
        pending = true;
      }
    }
  }
  return finish_hit(hit);
}
