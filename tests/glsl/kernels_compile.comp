#version 450
// Includes every single-source kernel the way the GPU port will, so that a construct that is C++ but
// not GLSL fails the test suite now rather than the GPU issue later.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 64) in;
#include "kernels/hit.h"
#include "kernels/layouts.h"
#include "kernels/line_space.h"
#include "kernels/ray_box.h"
#include "kernels/ray_triangle.h"
#include "kernels/offset_ray.h"
#include "kernels/scaled_geometry.h"
#include "kernels/rng.h"
#include "kernels/sampling.h"
#include "kernels/camera.h"
#include "kernels/throughput_switch.h"
layout(std430, binding = 0) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, binding = 1) readonly buffer Tris { Triangle tris[]; };
layout(std430, binding = 2) readonly buffer TriIds { uint tri_ids[]; };
layout(std430, binding = 3) readonly buffer TriInst { uint tri_instances[]; };
layout(std430, binding = 4) readonly buffer Top { BvhNode top_nodes[]; };
layout(std430, binding = 5) readonly buffer Inst { InstanceRecord instances[]; };
layout(std430, binding = 6) readonly buffer NodeLs { uint node_ls[]; };
layout(std430, binding = 7) readonly buffer LsNodes { LsNode ls_nodes[]; };
layout(std430, binding = 8) readonly buffer LsCand { uint ls_candidates[]; };
layout(std430, binding = 9) readonly buffer Records { LsRecord ls_records[]; };
layout(std430, binding = 10) buffer Rays { Ray rays[]; };
layout(std430, binding = 11) buffer Hits { Hit hits[]; };
layout(push_constant) uniform P { uint ls_enabled; uint ls_n; float ls_cos2; uint two_level; uint ls_behind; float ls_leave_reach; } pc;
uint ls_enabled = pc.ls_enabled; float ls_cos2 = pc.ls_cos2; uint ls_behind = pc.ls_behind;
float ls_leave_reach = pc.ls_leave_reach;
const uint walk_far_first = 0u;
LsCounters ls_counters;
void count_work(uint node, uint boxes, uint triangles) {}
#include "kernels/ls_lookup.h"
#include "kernels/traverse_bvh.h"
#include "kernels/ls_candidate_search.h"
void main() {
  uint i = gl_GlobalInvocationID.x;
  hits[i] = pc.two_level != 0u ? trace_two_level(rays[i], false) : trace_flat(rays[i], false);
}
