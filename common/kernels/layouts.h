// std430 structures shared by host and shaders, declared once (docs/design.md §4).  Each has the same size
// and member offsets in C++ (glm::vec3 = 12 bytes, 4-aligned) and in GLSL std430 (vec3 16-aligned):
// a vec3 is always followed by a 4-byte scalar so both layouts agree.  The static_asserts at the end
// hold the C++ side to the std430 sizes and offsets, and tests/test_layouts.cpp compares every struct
// with the offsets glslang gives it in SPIR-V.
#ifndef LS_LAYOUTS_H
#define LS_LAYOUTS_H

#include "glsl_compat.h"

#ifdef __cplusplus
namespace lsk {
#endif

// A ray record, identical to the ray file (docs/design.md §9): ox oy oz tmin dx dy dz tmax.
struct Ray {
  vec3 origin;
  float tmin;
  vec3 dir;
  float tmax;
};

// A hit record, identical to the hit file: t (+inf on a miss), instance, triangle (0xFFFFFFFF on a
// miss), u, v (barycentric weights of vertices 1 and 2).
struct Hit {
  float t;
  uint instance;
  uint triangle;
  float u;
  float v;
};

LS_CONST uint LS_INVALID = 0xFFFFFFFFu;

// A BVH node.  count > 0: a leaf holding primitives [first, first + count).  count == 0: an inner
// node whose children are the adjacent nodes `first` and `first + 1`.  Indices are absolute in the
// array the node lives in.  Every node's primitives are one contiguous range (the builder reorders
// them), so a subtree's triangles are [range_first, range_first + range_count) — used by the LS.
struct BvhNode {
  vec3 lo;
  uint first;
  vec3 hi;
  uint count;
};

// A triangle in the space of its BVH (object space for 2L-*, world space for F-*); w is unused (0).
struct Triangle {
  vec4 v0;
  vec4 v1;
  vec4 v2;
};

// One placed object of a two-level structure: the affine world-to-object transform (three rows),
// where its object's BVH starts, and its instance id.
struct InstanceRecord {
  vec4 world_to_object0;
  vec4 world_to_object1;
  vec4 world_to_object2;
  uint root;        // index of the object's root node in the nodes array
  uint instance;    // instance id (docs/design.md §9)
  uint object;      // index of the unique mesh
  uint pad;
};

// What a lookup reads of a candidate triangle (docs/design.md §3), precomputed by the host per
// triangle of the subtrees that get a Line Space: its plane and barycentric rows, so that the accept
// decision reads one record (one cache line: aligned to it on the host) and divides once.  For q = p - p0 of a point p on the
// plane, the barycentric coordinates are dot(q, b1) and dot(q, b2).  A degenerate triangle (or one
// whose rows overflow a float) has n = 0: the ray is parallel to it, and the lookup refuses.
struct LS_CACHE_LINE LsRecord {
  vec3 p0;       // the first vertex
  uint normal0;  // its vertex normal, octahedral (packSnorm2x16)
  vec3 n;        // the unit plane normal, cross(v1 - v0, v2 - v0) normalised
  uint normal1;
  vec3 b1;       // cross(e2, n) / |n|^2 in double, rounded: the row of the second vertex's weight
  uint normal2;
  vec3 b2;       // cross(n, e1) / |n|^2: the third vertex's
  uint id;       // tri_ids[] of the triangle
};

// A Line Space attached to one BVH node (docs/design.md §3).  Its box is the node's box, widened where it is
// thin so that a flat node (one quad) still has shafts that cross it.  Candidates are stored per shaft
// as an index local to the node's contiguous triangle range, in `bytes` bytes (1, 2 or 4, packed
// little-endian into 32-bit words; all ones = empty shaft).  Each node has its own subdivision N, so
// one structure can hold Line Spaces of different N (per-object parameters, 2l-ls:auto).
struct LsNode {
  vec3 lo;
  uint candidates;   // first 32-bit word of this node's candidates in ls_candidates[]
  vec3 hi;
  uint range_first;  // first triangle (index into tris[]) of the node's subtree
  vec3 scale;        // N / (hi - lo) per axis: patch coordinates without dividing on the device
  uint range_count;
  uint bytes;
  uint node;         // the BVH node it belongs to
  uint n;            // subdivision N: 30 N^4 shafts
  float inv_n;       // 1 / N, computed once by the host so that no device divides
};

// Counters of Line Space lookups, per trace call (summed by the host).
struct LsCounters {
  uint lookups;
  uint empty;             // empty shaft: no hit in the subtree
  uint accepted;          // the candidate's plane gave the hit
  uint refused_angle;     // extrapolated normal too far from the ray
  uint refused_behind;    // plane hit before the window: behind the origin (tmin), or before the node's box
  uint refused_beyond;    // plane hit after the window: beyond tmax as launched, or past the node's box
  uint refused_parallel;  // ray parallel to the candidate's plane
  uint refused_no_shaft;  // line along a face of the LS box (enters and leaves through one face)
};

// What a trace did, counted by the reference traversal (traverse_bvh.h): the work model of the Line
// Space budget's pilot (cpu/build/ls_budget.h) and of `linespace-validate bound`.  C++ only: the shaders
// count nothing.  The *_in_ls part was done at nodes in a Line Space node's subtree, the LS node
// included: the exact work below the lookups.
struct TraceWork {
  uint box_tests;
  uint triangle_tests;
  uint box_tests_in_ls;
  uint triangle_tests_in_ls;
};

// A pinhole camera: world position, orthonormal frame, tan(vertical fov / 2), image size.
struct CameraFrame {
  vec3 position;
  float tan_half_fov;
  vec3 right;
  float aspect;  // width / height
  vec3 up;
  uint width;
  vec3 forward;
  uint height;
};


// The path tracer's shading data (common/kernels/shade_path.h), built once per render by the host.
// A placed mesh: object-to-world columns (affine: col3 is the translation), the normal matrix's
// columns (transpose of the inverse of the upper 3x3), and where its vertices and triangles start.
struct ShadeInstance {
  vec3 col0;
  uint first_vertex;
  vec3 col1;
  uint first_triangle;
  vec3 col2;
  uint pad0;
  vec3 col3;
  uint pad1;
  vec3 ncol0;
  uint pad2;
  vec3 ncol1;
  uint pad3;
  vec3 ncol2;
  uint pad4;
};

// A mesh vertex in object space: position and unit vertex normal.
struct ShadeVertex {
  vec3 position;
  uint pad0;
  vec3 normal;
  uint pad1;
};

// A mesh triangle: absolute indices into the vertices, and its material.
struct ShadeTriangle {
  uvec3 idx;
  uint material;
};

// A Lambertian material: reflectance and emitted radiance (non-zero: an area light).
struct ShadeMaterial {
  vec3 albedo;
  uint pad0;
  vec3 emission;
  uint pad1;
};

// An emissive world triangle, picked for next-event estimation by the CDF light_cdf[] (by power);
// its area is in scene units (kernels/scaled_geometry.h), its normal unit length.
struct ShadeLight {
  vec3 a;
  float area;
  vec3 b;
  uint pad0;
  vec3 c;
  uint pad1;
  vec3 normal;
  uint pad2;
  vec3 emission;
  uint pad3;
};

// Per-render constants of the shading kernel.
struct ShadeParams {
  vec3 background;    // radiance of rays that leave the scene
  float scene_scale;  // ray-offset scale (power of two >= largest absolute world coordinate)
  uint seed;
  uint light_count;
  float total_power;  // sum of area x luminance(emission) over the lights
  uint bounces;       // the last bounce: its light sample takes the full weight, no further segment
  int unit_k;         // scene units = world lengths x 2^unit_k (kernels/scaled_geometry.h)
  uint pad0;
  uint pad1;
  uint pad2;
};

// One path of the wavefront (one pixel): the segment to trace, the shadow ray of the current bounce
// and what it carries, the throughput and the density of the direction that made `ray` (MIS), and
// whether this bounce's rays are traced with the throughput switch's structure (throughput_switch.h).
struct PathState {
  Ray ray;
  Ray shadow_ray;
  vec3 throughput;
  float bsdf_pdf;
  vec3 shadow_contribution;
  uint alive;
  uint has_shadow;
  uint switched;
  uint pad1;
  uint pad2;
};

// The push constants of trace.comp and ls_candidates.comp (gpu/shaders/scene_buffers.glsl declares
// the block's one member `pc` of this type).
struct ShaderParams {
  uint ls_enabled;       // trace: use the Line Space
  uint ls_n;             // candidates: N of this dispatch's LS nodes (the result stride)
  float ls_cos2;         // cos^2 of the refusal angle (negative: refuse all)
  uint two_level;        // trace: 2L structure
  uint any_hit;          // trace: stop at the first hit
  uint first;            // trace: first ray of this dispatch
  uint count;            // trace: rays in the buffer
  uint ls_behind;        // trace: --ls-behind, LS_BEHIND_* (ls_lookup.h)
  uint further_rays;     // candidates: search rays after the midpoint ray
  uint search_instance;  // candidates: 0 (2L) or LS_INVALID (F)
  uint first_ls;         // candidates: first LS node of this dispatch
  uint ls_count;         // candidates: LS nodes in this dispatch
  float ls_leave_reach;  // trace: --ls-leave-reach, patches (ls_lookup.h)
};

// The push constants of shade.comp (its block's one member `pc`).
struct ShadePush {
  uint mode;
  uint sample_index;
  uint bounce;
  uint count;               // batch entries: pixels to start (mode 0), hits to shade (modes 1, 2)
  uint image_offset;        // first float of this bounce's image
  uint list_kind;           // mode 3: 0 extension rays (decide), 1 shadow rays (as decided)
  float switch_threshold;   // mode 3: the throughput switch's T
  uint pad0;
};

// Binding 6 of shade.comp: what every invocation of a render reads.
struct ShadeConstants {
  ShadeParams shade;
  CameraFrame cam;
};

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
