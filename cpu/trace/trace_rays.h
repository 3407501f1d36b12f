// Tracing a built structure on the CPU: one ray through the reference kernels, or batches on all
// threads by the fast path (fast_tracer.h) or the reference, with Line Space counters and the
// reference's work counts.
#pragma once

#include "common/structure/accel.h"
#include "common/structure/trace_context.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ls {

// One ray.  The first form discards Line Space counters; the second adds them to context.ls_counters.
lsk::Hit trace_ray(const lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit);
lsk::Hit trace_ray_counted(lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit);

// Traces a batch on all threads (TBB) with accel.traversal, every Line Space lookup as `lookup` says;
// Line Space counters are added to *counters when given.  The second form names the traversal (bench
// and tests run both on one structure).
void trace_rays(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
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
// reference traversal fitted over seven structures (docs/performance.md, "Per-object Line Space under
// a memory budget").
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
void trace_rays(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters, Traversal traversal, TraceWorkTotals* work = nullptr,
                const std::vector<uint8_t>* ls_subtrees = nullptr);

// Occlusion queries (shadow rays) on all threads: a ray misses exactly where trace_rays' any hit
// misses; where it is blocked its hit record is *a* hit in [tmin, tmax] (on the fast path not
// necessarily the reference's first: FastTracer::occluded).  The path tracer's shadow rays use it.
void trace_occlusion(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters = nullptr);
void trace_occlusion(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters,
                     Traversal traversal);


}  // namespace ls
