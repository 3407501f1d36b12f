// The path tracer's per-path steps (cpu/render/path_tracer.h), once for CPU and GPU (docs/design.md §4): start a
// path at the camera, shade the hit of its segment (surface, MIS-weighted emission, a light sample for
// next-event estimation with its shadow ray, the next direction) and add a shadow ray's light.
//
// Meant to be included where the shading buffers are in scope under these names: inside
// lsk::ShadeContext (common/render/shade_context.h) on the CPU, at global scope in gpu/shaders/*.comp:
//   shade_instances[] (ShadeInstance), shade_vertices[] (ShadeVertex), shade_triangles[]
//   (ShadeTriangle), materials[] (ShadeMaterial), lights[] (ShadeLight), light_cdf[] (float,
//   inclusive, last == 1) and `shade` (ShadeParams).
//
// Every sum and product is spelled out in the order GLM evaluates it (mat4 * vec4, mat3 * vec3, dot,
// cross, length = sqrt(dot), normalize = v * (1 / sqrt(dot))), so the CPU keeps its earlier results bit
// for bit and lavapipe, which rounds each operation like the CPU, gives the same.  sqrt, division, sin
// and cos are not portable to real GPUs (docs/design.md §11): there the paths agree, not their last bits.
#ifndef LS_SHADE_PATH_H
#define LS_SHADE_PATH_H

#include "camera.h"
#include "float_bits.h"
#include "layouts.h"
#include "offset_ray.h"
#include "rng.h"
#include "sampling.h"
#include "scaled_geometry.h"

// Random dimensions used at each bounce.
LS_CONST uint LS_DIM_PIXEL_X = 0u;
LS_CONST uint LS_DIM_PIXEL_Y = 1u;
LS_CONST uint LS_DIM_LIGHT_PICK = 2u;
LS_CONST uint LS_DIM_LIGHT_U = 3u;
LS_CONST uint LS_DIM_LIGHT_V = 4u;
LS_CONST uint LS_DIM_BSDF_U = 5u;
LS_CONST uint LS_DIM_BSDF_V = 6u;

LS_FN bool finite3(IN(vec3) v) {
  return !(isinf(v.x) || isnan(v.x) || isinf(v.y) || isnan(v.y) || isinf(v.z) || isnan(v.z));
}

// (c0 x + c1 y) + (c2 z + c3): GLM's mat4 * vec4(p, 1).
LS_FN vec3 instance_point(IN(ShadeInstance) inst, IN(vec3) p) {
  precise vec3 s01 = inst.col0 * p.x + inst.col1 * p.y;
  precise vec3 s23 = inst.col2 * p.z + inst.col3;
  precise vec3 r = s01 + s23;
  return r;
}

// c0 x + c1 y + c2 z: GLM's mat3 * vec3.
LS_FN vec3 instance_normal(IN(ShadeInstance) inst, IN(vec3) n) {
  precise vec3 r = inst.ncol0 * n.x + inst.ncol1 * n.y + inst.ncol2 * n.z;
  return r;
}

// Adds a contribution to a pixel, or counts it as dropped when the sum is not finite (two huge
// finite contributions can add up to infinity).
LS_FN void add_contribution(INOUT(vec3) pixel, INOUT(uint) dropped, IN(vec3) c) {
  precise vec3 sum = pixel + c;
  if (finite3(sum)) {
    pixel = sum;
  } else {
    dropped = dropped + 1u;
  }
}

// The first light whose inclusive CDF exceeds u (upper bound), the last one at most.
LS_FN uint pick_light(float u) {
  uint lo = 0u;
  uint hi = shade.light_count;
  while (lo < hi) {
    uint mid = lo + (hi - lo) / 2u;
    if (light_cdf[mid] > u) hi = mid;
    else lo = mid + 1u;
  }
  return min(lo, shade.light_count - 1u);
}

// Density, per unit area, of sampling a point on an emissive triangle of emission e.
LS_FN float light_area_pdf(IN(vec3) e) { return shade.total_power > 0.0f ? luminance(e) / shade.total_power : 0.0f; }

// The camera ray of pixel p for one sample: a fresh path.
LS_FN void start_path(uint p, uint sample_index, IN(CameraFrame) cam, OUT(PathState) path) {
  precise float x = float(p % cam.width) + random01(shade.seed, p, sample_index, 0u, LS_DIM_PIXEL_X);
  precise float y = float(p / cam.width) + random01(shade.seed, p, sample_index, 0u, LS_DIM_PIXEL_Y);
  path.ray = camera_ray(cam, x, y);
  path.shadow_ray = path.ray;
  path.throughput = vec3(1.0f, 1.0f, 1.0f);
  path.bsdf_pdf = 0.0f;
  path.shadow_contribution = vec3(0.0f, 0.0f, 0.0f);
  path.alive = 1u;
  path.has_shadow = 0u;
  path.switched = 0u;
  path.pad1 = 0u;
  path.pad2 = 0u;
}

// The surface at a hit (triangle != LS_INVALID) of a ray with direction ray_dir: world position, unit
// geometric normal facing the ray's side, unit shading normal on that side, material.
LS_FN void surface_at(IN(Hit) hit, IN(vec3) ray_dir, OUT(vec3) position, OUT(vec3) geometric_normal,
                      OUT(vec3) shading_normal, OUT(uint) material) {
  ShadeInstance inst = shade_instances[hit.instance];
  ShadeTriangle tri = shade_triangles[inst.first_triangle + hit.triangle];
  vec3 a = instance_point(inst, shade_vertices[tri.idx.x].position);
  vec3 b = instance_point(inst, shade_vertices[tri.idx.y].position);
  vec3 c = instance_point(inst, shade_vertices[tri.idx.z].position);
  precise float w0 = 1.0f - hit.u - hit.v;
  precise vec3 pos = a * w0 + b * hit.u + c * hit.v;
  position = pos;
  // Edges scaled by a power of two first: at 1e20 or 1e-20 a float cross product over- or underflows.
  precise vec3 e1 = b - a;
  precise vec3 e2 = c - a;
  int k = unit_exponent(max(max_abs(e1), max_abs(e2)));
  vec3 ng = cross_in_order(scale_pow2(e1, k), scale_pow2(e2, k));
  float len = length_in_order(ng);
  if (len > 0.0f && !isinf(len) && !isnan(len)) {
    precise vec3 q = ng / len;
    ng = q;
  } else {
    ng = -normalize_in_order(ray_dir);
  }
  if (dot_in_order(ng, ray_dir) > 0.0f) ng = -ng;
  precise vec3 nsum = shade_vertices[tri.idx.x].normal * w0 + shade_vertices[tri.idx.y].normal * hit.u +
                      shade_vertices[tri.idx.z].normal * hit.v;
  vec3 ns = normalize_any(instance_normal(inst, nsum));  // a 1e-20 scale's normal matrix holds 1e20
  precise float ns_sum = ns.x + ns.y + ns.z;
  if ((ns.x == 0.0f && ns.y == 0.0f && ns.z == 0.0f) || isinf(ns_sum) || isnan(ns_sum)) ns = ng;
  if (dot_in_order(ns, ng) < 0.0f) ns = -ns;
  geometric_normal = ng;
  shading_normal = ns;
  material = tri.material;
}

// Shades the hit of path p's segment at `bounce`: adds what it found to `pixel` (the bounce image),
// prepares the shadow ray of its light sample (has_shadow) and the next segment (alive).
LS_FN void shade_path(uint p, uint sample_index, uint bounce, IN(Hit) hit, INOUT(PathState) path, INOUT(vec3) pixel,
                      INOUT(uint) dropped) {
  path.has_shadow = 0u;
  if (hit.triangle == LS_INVALID) {
    precise vec3 c = path.throughput * shade.background;
    add_contribution(pixel, dropped, c);
    path.alive = 0u;
    return;
  }
  vec3 position;
  vec3 n;
  vec3 shading_normal;
  uint material;
  surface_at(hit, path.ray.dir, position, n, shading_normal, material);
  ShadeMaterial mat = materials[material];
  if (luminance(mat.emission) > 0.0f) {
    float weight = 1.0f;
    if (bounce > 0u) {
      precise float dist = to_scene_units(hit.t * length_in_order(path.ray.dir), shade.unit_k);
      float cos_l = abs(dot_in_order(n, normalize_in_order(path.ray.dir)));
      precise float light_pdf = cos_l > 0.0f ? light_area_pdf(mat.emission) * dist * dist / cos_l : 0.0f;
      weight = power_heuristic(path.bsdf_pdf, light_pdf);
    }
    precise vec3 c = path.throughput * mat.emission * weight;
    add_contribution(pixel, dropped, c);
  }
  vec3 origin = offset_ray_origin(position, n, shade.scene_scale);
  if (shade.light_count > 0u) {
    ShadeLight l = lights[pick_light(random01(shade.seed, p, sample_index, bounce, LS_DIM_LIGHT_PICK))];
    vec3 q = sample_triangle(l.a, l.b, l.c, random01(shade.seed, p, sample_index, bounce, LS_DIM_LIGHT_U),
                             random01(shade.seed, p, sample_index, bounce, LS_DIM_LIGHT_V));
    vec3 nl = l.normal;
    precise vec3 to_origin = origin - q;
    if (dot_in_order(nl, to_origin) < 0.0f) nl = -nl;
    vec3 target = offset_ray_origin(q, nl, shade.scene_scale);
    precise vec3 d = target - origin;
    vec3 d_units = to_scene_units(d, shade.unit_k);  // exact: a power of two; keeps dist2 finite
    float dist2 = dot_in_order(d_units, d_units);
    precise vec3 wi = d_units / sqrt(dist2);
    float cos_s = dot_in_order(n, wi);
    float cos_l = dot_in_order(nl, -wi);
    if (cos_s > 0.0f && cos_l > 0.0f && dist2 > 0.0f) {
      precise float light_pdf = light_area_pdf(l.emission) * dist2 / cos_l;
      precise float bsdf_pdf = cos_s / LS_PI;
      // The last bounce traces no further segment to find this light by BSDF sampling, so its light
      // sample carries the whole weight.
      float weight = bounce == shade.bounces ? 1.0f : power_heuristic(light_pdf, bsdf_pdf);
      path.shadow_ray.origin = origin;
      path.shadow_ray.dir = d;
      path.shadow_ray.tmin = 0.0f;
      path.shadow_ray.tmax = 1.0f;
      precise float s = cos_s * weight / light_pdf;
      precise vec3 c = path.throughput * (mat.albedo / LS_PI) * l.emission * s;
      path.shadow_contribution = c;
      path.has_shadow = 1u;
    }
  }
  if (bounce == shade.bounces) {
    path.alive = 0u;
    return;
  }
  vec3 dir = sample_cosine_hemisphere(n, random01(shade.seed, p, sample_index, bounce, LS_DIM_BSDF_U),
                                      random01(shade.seed, p, sample_index, bounce, LS_DIM_BSDF_V));
  float cos_o = dot_in_order(n, dir);
  if (!(cos_o > 0.0f)) {
    path.alive = 0u;
    return;
  }
  path.ray.origin = origin;
  path.ray.dir = dir;
  path.ray.tmin = 0.0f;
  path.ray.tmax = ls_infinity();
  precise float pdf = cos_o / LS_PI;
  path.bsdf_pdf = pdf;
  precise vec3 t = path.throughput * mat.albedo;  // albedo/pi * cos / (cos/pi)
  path.throughput = t;
  if (!(luminance(path.throughput) > 0.0f)) path.alive = 0u;
}

// Adds the light of path's shadow ray, which reached its light unblocked.
LS_FN void add_shadow_light(IN(PathState) path, INOUT(vec3) pixel, INOUT(uint) dropped) {
  add_contribution(pixel, dropped, path.shadow_contribution);
}

#endif
