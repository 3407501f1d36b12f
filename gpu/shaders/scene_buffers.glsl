// The scene's buffers, named like the pointer members of lsk::TraceContext
// (common/structure/trace_context.h) so that the single-source kernels read them unchanged, plus the
// parameters every kernel receives (lsk::ShaderParams, common/kernels/layouts.h).  The host binds them
// in this order (gpu/gpu_accel.cpp).
#include "kernels/hit.h"
#include "kernels/layouts.h"
#include "kernels/line_space.h"
#include "kernels/ray_box.h"
#include "kernels/ray_triangle.h"

layout(std430, binding = 0) readonly buffer Nodes { BvhNode nodes[]; };
layout(std430, binding = 1) readonly buffer Tris { Triangle tris[]; };
layout(std430, binding = 2) readonly buffer TriIds { uint tri_ids[]; };
layout(std430, binding = 3) readonly buffer TriInstances { uint tri_instances[]; };
layout(std430, binding = 4) readonly buffer TopNodes { BvhNode top_nodes[]; };
layout(std430, binding = 5) readonly buffer Instances { InstanceRecord instances[]; };
layout(std430, binding = 6) readonly buffer NodeLs { uint node_ls[]; };
layout(std430, binding = 7) readonly buffer LsNodes { LsNode ls_nodes[]; };
layout(std430, binding = 8) readonly buffer LsCandidates { uint ls_candidates[]; };
layout(std430, binding = 9) readonly buffer LsRecords { LsRecord ls_records[]; };

layout(push_constant) uniform Params { ShaderParams pc; };  // common/kernels/layouts.h

uint ls_enabled = pc.ls_enabled;
float ls_cos2 = pc.ls_cos2;
uint ls_behind = pc.ls_behind;
float ls_leave_reach = pc.ls_leave_reach;
const uint walk_far_first = 0u;  // the CPU's tests' order switch (traverse_bvh.h)
LsCounters ls_counters;
void count_work(uint node, uint boxes, uint triangles) {}  // the CPU's work counters (traverse_bvh.h)

#include "kernels/ls_lookup.h"
#include "kernels/traverse_bvh.h"
