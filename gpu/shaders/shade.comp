#version 450
// The path tracer's wavefront steps on the GPU, one invocation per path (common/kernels/shade_path.h,
// the kernel the CPU renderer calls):
//   mode 0: start the path of every listed pixel (batch_pixels: all, or a shard's tiles) at the camera
//           and list its ray for bounce 0;
//   mode 1: shade the hits of the listed paths, add what they found to the bounce image, and append
//           their shadow rays and next segments (atomically; the order of a batch changes no image);
//   mode 2: add the light of the shadow rays that reached their light;
//   mode 3: with the throughput switch on, split a list of this bounce's rays: the paths that follow
//           the schedule to the first output list (next_*), the switched ones to the second (shadow_*).
//           For extension rays (list_kind 0) it decides first (kernels/throughput_switch.h) and keeps
//           the decision in the path for its shadow ray (list_kind 1).
// The host (gpu/gpu_renderer.cpp) traces the lists with trace.comp between these steps.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "kernels/layouts.h"

layout(std430, binding = 0) readonly buffer ShadeInstances { ShadeInstance shade_instances[]; };
layout(std430, binding = 1) readonly buffer ShadeVertices { ShadeVertex shade_vertices[]; };
layout(std430, binding = 2) readonly buffer ShadeTriangles { ShadeTriangle shade_triangles[]; };
layout(std430, binding = 3) readonly buffer Materials { ShadeMaterial materials[]; };
layout(std430, binding = 4) readonly buffer Lights { ShadeLight lights[]; };
layout(std430, binding = 5) readonly buffer LightCdf { float light_cdf[]; };
layout(std430, binding = 6) readonly buffer Constants { ShadeConstants constants; };
ShadeParams shade = constants.shade;  // the name the kernels read (ShadeContext::shade on the CPU)
CameraFrame cam = constants.cam;
layout(std430, binding = 7) buffer Paths { PathState paths[]; };
layout(std430, binding = 8) buffer Images { float images[]; };       // (bounces + 1) x pixels x RGB, sums
layout(std430, binding = 9) buffer Dropped { uint dropped[]; };      // per pixel
layout(std430, binding = 10) readonly buffer BatchPixels { uint batch_pixels[]; };
layout(std430, binding = 11) readonly buffer BatchHits { Hit batch_hits[]; };
layout(std430, binding = 12) writeonly buffer NextRays { Ray next_rays[]; };
layout(std430, binding = 13) writeonly buffer NextPixels { uint next_pixels[]; };
layout(std430, binding = 14) writeonly buffer ShadowRays { Ray shadow_rays[]; };
layout(std430, binding = 15) writeonly buffer ShadowPixels { uint shadow_pixels[]; };
layout(std430, binding = 16) buffer Counts { uint next_count; uint shadow_count; };

layout(push_constant) uniform Push { ShadePush pc; };  // common/kernels/layouts.h

#include "kernels/shade_path.h"
#include "kernels/throughput_switch.h"

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  uint p = batch_pixels[i];
  if (pc.mode == 0u) {
    PathState path;
    start_path(p, pc.sample_index, cam, path);
    paths[p] = path;
    next_rays[i] = path.ray;
    next_pixels[i] = p;
    return;
  }
  if (pc.mode == 3u) {
    if (pc.list_kind == 0u) paths[p].switched = throughput_switched(paths[p].throughput, pc.switch_threshold);
    Ray ray = pc.list_kind == 0u ? paths[p].ray : paths[p].shadow_ray;
    if (paths[p].switched != 0u) {
      uint j = atomicAdd(shadow_count, 1u);
      shadow_rays[j] = ray;
      shadow_pixels[j] = p;
    } else {
      uint j = atomicAdd(next_count, 1u);
      next_rays[j] = ray;
      next_pixels[j] = p;
    }
    return;
  }
  uint base = pc.image_offset + 3u * p;
  vec3 pixel = vec3(images[base], images[base + 1u], images[base + 2u]);
  uint d = dropped[p];
  if (pc.mode == 1u) {
    PathState path = paths[p];
    shade_path(p, pc.sample_index, pc.bounce, batch_hits[i], path, pixel, d);
    paths[p] = path;
    if (path.has_shadow != 0u) {
      uint j = atomicAdd(shadow_count, 1u);
      shadow_rays[j] = path.shadow_ray;
      shadow_pixels[j] = p;
    }
    if (path.alive != 0u) {
      uint j = atomicAdd(next_count, 1u);
      next_rays[j] = path.ray;
      next_pixels[j] = p;
    }
  } else {
    if (batch_hits[i].triangle != LS_INVALID) return;
    add_shadow_light(paths[p], pixel, d);
  }
  images[base] = pixel.x;
  images[base + 1u] = pixel.y;
  images[base + 2u] = pixel.z;
  dropped[p] = d;
}
