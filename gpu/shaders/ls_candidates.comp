#version 450
// The Line Space candidate search on the GPU: invocation (shaft, slot) searches shaft `shaft` of LS
// node first_ls + slot with the single-source kernel (common/kernels/ls_candidate_search.h) and writes
// the tris[] index it found (LS_INVALID: empty).  The host packs the result with the CPU builder's
// pack_ls_candidates(), so both back ends share one packing rule.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "scene_buffers.glsl"
#include "kernels/ls_candidate_search.h"

layout(std430, binding = 10) writeonly buffer Prims { uint prims[]; };

void main() {
  uint shafts = ls_shaft_count(pc.ls_n);
  uint shaft = gl_GlobalInvocationID.x;
  uint slot = gl_GlobalInvocationID.y;
  if (shaft >= shafts || slot >= pc.ls_count) return;
  LsNode ls = ls_nodes[pc.first_ls + slot];
  prims[slot * shafts + shaft] = ls_find_candidate(ls.node, ls, shaft, pc.further_rays, pc.search_instance);
}
