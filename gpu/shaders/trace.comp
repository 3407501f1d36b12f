#version 450
// Traces rays[first + gid] against the structure in the scene buffers: closest or any hit, exactly
// like ls::trace_rays on the CPU (the same kernels, common/kernels/traverse_bvh.h and ls_lookup.h).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "scene_buffers.glsl"

layout(std430, binding = 10) readonly buffer Rays { Ray rays[]; };
layout(std430, binding = 11) writeonly buffer Hits { Hit hits[]; };
layout(std430, binding = 12) buffer Counters { uint counters[8]; };  // LsCounters, summed

void main() {
  uint i = pc.first + gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  ls_counters.lookups = 0u;
  ls_counters.empty = 0u;
  ls_counters.accepted = 0u;
  ls_counters.refused_angle = 0u;
  ls_counters.refused_behind = 0u;
  ls_counters.refused_beyond = 0u;
  ls_counters.refused_parallel = 0u;
  ls_counters.refused_no_shaft = 0u;
  bool any_hit = pc.any_hit != 0u;
  hits[i] = pc.two_level != 0u ? trace_two_level(rays[i], any_hit) : trace_flat(rays[i], any_hit);
  if (ls_counters.lookups != 0u) {
    atomicAdd(counters[0], ls_counters.lookups);
    atomicAdd(counters[1], ls_counters.empty);
    atomicAdd(counters[2], ls_counters.accepted);
    atomicAdd(counters[3], ls_counters.refused_angle);
    atomicAdd(counters[4], ls_counters.refused_behind);
    atomicAdd(counters[5], ls_counters.refused_beyond);
    atomicAdd(counters[6], ls_counters.refused_parallel);
    atomicAdd(counters[7], ls_counters.refused_no_shaft);
  }
}
