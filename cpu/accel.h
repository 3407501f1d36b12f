// An acceleration structure ready to trace: the flat BVH (F-BVH) over world-space triangles, or the
// two-level BVH (2L-BVH): one BVH per unique mesh in object space plus a top-level BVH over instances.
// The arrays are the std430 buffers the GPU port uploads unchanged.
#pragma once

#include "bvh_builder.h"
#include "fast_tracer.h"
#include "line_space_builder.h"
#include "ls_budget.h"
#include "scene.h"
#include "structure_name.h"
#include "trace_context.h"

#include <cstddef>
#include <memory>
#include <vector>

namespace ls {

struct Accel {
  StructureSpec spec;
  std::vector<lsk::BvhNode> nodes;          // F: the flat BVH; 2L: every object BVH, one after another
  std::vector<lsk::Triangle> tris;          // in BVH order
  std::vector<uint32_t> tri_ids;            // triangle id within its mesh
  std::vector<uint32_t> tri_instances;      // F only: instance id per triangle
  std::vector<lsk::BvhNode> top_nodes;      // 2L only
  std::vector<lsk::InstanceRecord> instances;  // 2L only, in top-level order
  std::vector<uint32_t> object_roots;       // 2L only: root node of each unique mesh's BVH (by mesh index;
                                            // LS_INVALID for meshes no instance uses)
  size_t objects = 0;                       // unique meshes the structure holds
  size_t instance_count = 0;
  size_t world_triangles = 0;
  int max_depth = 0;                        // deepest BVH (object BVHs for 2L)
  double build_seconds = 0.0;               // everything, Line Space included
  BvhBuildOptions bvh_options;              // what the BVHs were built with (the top level is rebuilt with it)
  // Which build this is (unique per build_accel call in a process; 0 for hand-made structures) and
  // how often its top level was updated since (top_level_update.h): device copies check both.
  uint64_t build_id = 0;
  uint32_t top_level_version = 0;

  // Line Space (F-LS, 2L-LS): see line_space_builder.h and common/kernels/ls_lookup.h.
  std::vector<uint32_t> node_ls;            // per BVH node: its LsNode, or LS_INVALID
  std::vector<lsk::LsNode> ls_nodes;
  std::vector<uint32_t> ls_candidates;      // packed per LsNode
  std::vector<glm::uvec4> tri_normals;      // octahedral vertex normals per triangle (BVH order)
  LsOptions ls_options;
  LsBuildInfo ls_info;
  std::shared_ptr<const LsPlan> ls_plan;    // 2l-ls:auto: the per-object choice (ls_budget.h)

  // The fast CPU path (fast_tracer.h): the wide BVH over the arrays above, and which path trace_rays
  // takes by default.  Both give the same answers; the reference is the GPU's twin.
  std::shared_ptr<const FastTracer> fast;
  Traversal traversal = Traversal::Fast;
  double wide_build_seconds = 0.0;          // part of build_seconds

  size_t bytes_total() const;
  size_t bytes_wide() const;                // the fast path's wide nodes (beside bytes_total)
  size_t bytes_ls() const;
  lsk::TraceContext context() const;
};

struct AccelOptions {
  BvhBuildOptions bvh;
  LsOptions ls;
  bool search_candidates = true;  // false: the Line Space is laid out with every shaft empty (GPU search)
  Traversal traversal = Traversal::Fast;  // what trace_rays uses for this structure
  int wide_width = 4;                     // treelets (Line Space structures): 4 or 8, chosen by measurement
  int exact_width = 8;                    // the order-free walk's nodes: 4 or 8, chosen by measurement
  bool fast_path = true;  // false: no fast path is made, trace_rays takes the reference (the GPU port's builds)
  AccelOptions() = default;
  AccelOptions(const BvhBuildOptions& b) : bvh(b) {}  // NOLINT: implicit on purpose
};

// Builds any of the four structures of DESIGN §3.
Accel build_accel(const Scene& scene, const StructureSpec& spec, const AccelOptions& options = {});

// One ray.  The first form discards Line Space counters; the second adds them to context.ls_counters.
lsk::Hit trace_ray(const lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit);
lsk::Hit trace_ray_counted(lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit);

// The reference kernels on one ray (flat or two-level) and on one BVH (an object-space ray), for the
// fast path's fallbacks (fast_tracer.h).  Compiled here, not in fast_tracer.cpp: the kernels
// instantiated there took GCC's inlining budget from the fast walks (5 % more instructions a ray).
lsk::Hit trace_ray_reference(lsk::TraceContext& context, const lsk::Ray& ray, bool two_level, bool any_hit);
bool trace_bvh_reference(lsk::TraceContext& context, uint32_t root, const lsk::vec3& origin, const lsk::vec3& dir,
                         float tmin, uint32_t instance, bool any_hit, bool use_ls, lsk::Hit& hit, uint32_t& hit_prim);

// Traces a batch on all threads (TBB) with accel.traversal; Line Space counters are added to *counters
// when given.  The second form names the traversal (bench and tests run both on one structure).
void trace_rays(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters = nullptr);
// The reference traversal's work over a batch (the 2l-ls:auto pilot's model, ls_budget.h): box and
// triangle tests counted by the kernels, Line Space lookups by the counters.  The fast path counts
// only what it hands to the reference kernels (its own box tests are SIMD lanes the kernels do not
// see).  The *_in_ls part was done in Line Space nodes' subtrees (line_space_subtrees).
struct TraceWorkTotals {
  uint64_t box_tests = 0, triangle_tests = 0, lookups = 0;
  uint64_t box_tests_in_ls = 0, triangle_tests_in_ls = 0;
};
// That work in box tests: a triangle test and a Line Space lookup weighed by instruction counts of the
// reference traversal fitted over seven structures (README, "2l-ls:auto").
constexpr double kTriangleTestWork = 2.3;
constexpr double kLookupWork = 5.7;
inline double work_units(uint64_t box_tests, uint64_t triangle_tests, uint64_t lookups) {
  return double(box_tests) + kTriangleTestWork * double(triangle_tests) + kLookupWork * double(lookups);
}
// Per node of accel.nodes: 1 in the subtree of a node with a Line Space (that node included), else
// 0.  Empty for a structure without a Line Space.
std::vector<uint8_t> line_space_subtrees(const Accel& accel);
// ls_subtrees (line_space_subtrees of accel): the work done in those subtrees is also counted as
// work->*_in_ls; without it they stay 0.
void trace_rays(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters, Traversal traversal, TraceWorkTotals* work = nullptr,
                const std::vector<uint8_t>* ls_subtrees = nullptr);

// Occlusion queries (shadow rays) on all threads: a ray misses exactly where trace_rays' any hit
// misses; where it is blocked its hit record is *a* hit in [tmin, tmax] (on the fast path not
// necessarily the reference's first: FastTracer::occluded).  The path tracer's shadow rays use it.
void trace_occlusion(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters = nullptr);
void trace_occlusion(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters,
                     Traversal traversal);

void add_counters(lsk::LsCounters& into, const lsk::LsCounters& from);

}  // namespace ls
