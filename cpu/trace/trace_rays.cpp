#include "cpu/trace/trace_rays.h"

#include "common/base/parallel.h"
#include "common/structure/accel.h"
#include "cpu/trace/fast_tracer.h"
#include "cpu/trace/reference_trace.h"

#include <tbb/enumerable_thread_specific.h>

namespace ls {

lsk::Hit trace_ray_counted(lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit) {
  return trace_ray_reference(context, ray, accel.spec.two_level(), any_hit);
}

lsk::Hit trace_ray(const lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit) {
  lsk::TraceContext c = context;
  return trace_ray_counted(c, accel, ray, any_hit);
}


void trace_rays(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters) {
  trace_rays(accel, lookup, rays, hits, count, any_hit, counters, accel.traversal);
}

std::vector<uint8_t> line_space_subtrees(const Accel& accel) {
  std::vector<uint8_t> in_ls;
  if (accel.node_ls.empty()) return in_ls;
  in_ls.assign(accel.nodes.size(), 0);
  std::vector<uint32_t> stack;
  for (size_t n = 0; n != accel.nodes.size(); ++n) {
    if (accel.node_ls[n] == lsk::LS_INVALID || in_ls[n]) continue;
    stack.assign(1, uint32_t(n));
    while (!stack.empty()) {
      const uint32_t i = stack.back();
      stack.pop_back();
      in_ls[i] = 1;
      const lsk::BvhNode& node = accel.nodes[i];
      if (node.count == 0) {
        stack.push_back(node.first);
        stack.push_back(node.first + 1);
      }
    }
  }
  return in_ls;
}

namespace {

// trace_rays and trace_occlusion: TBB over chunks of rays, each chunk on its own copy of the trace
// context, counters per thread and summed once.
void trace_chunks(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit, bool occlusion,
                  lsk::LsCounters* counters, Traversal traversal, TraceWorkTotals* work,
                  const std::vector<uint8_t>* ls_subtrees) {
  lsk::TraceContext context = trace_context(accel, lookup);
  // The fast path's any hit runs the reference kernels, which know nothing of --skip.
  if (lookup.skip != LsSkip::Nothing && (traversal != Traversal::Fast || !accel.fast || (any_hit && !occlusion)))
    throw InputError("--skip times the fast path's closest-hit and occlusion queries only");
  if (work && ls_subtrees && !ls_subtrees->empty()) context.node_in_ls = ls_subtrees->data();
  const FastTracer* fast = traversal == Traversal::Fast ? accel.fast.get() : nullptr;  // none: hand-made Accel
  // Per-thread counters, summed once at the end: no lock on the hot path.
  tbb::enumerable_thread_specific<lsk::LsCounters> per_thread(lsk::LsCounters{});
  tbb::enumerable_thread_specific<TraceWorkTotals> per_thread_work;
  ls::parallel_for(tbb::blocked_range<size_t>(0, count, 256), [&](const tbb::blocked_range<size_t>& r) {
    lsk::TraceContext local = context;
    if (fast && occlusion)
      fast->occluded(local, rays + r.begin(), hits + r.begin(), r.size());
    else if (fast)
      fast->trace(local, rays + r.begin(), hits + r.begin(), r.size(), any_hit);
    else
      for (size_t i = r.begin(); i != r.end(); ++i) hits[i] = trace_ray_counted(local, accel, rays[i], any_hit);
    if (counters && accel.spec.line_space()) add_counters(per_thread.local(), local.ls_counters);
    if (work) {
      TraceWorkTotals& w = per_thread_work.local();
      w.box_tests += local.trace_work.box_tests;
      w.triangle_tests += local.trace_work.triangle_tests;
      w.lookups += local.ls_counters.lookups;
      w.box_tests_in_ls += local.trace_work.box_tests_in_ls;
      w.triangle_tests_in_ls += local.trace_work.triangle_tests_in_ls;
    }
  });
  if (counters)
    for (const lsk::LsCounters& c : per_thread) add_counters(*counters, c);
  if (work)
    for (const TraceWorkTotals& w : per_thread_work) {
      work->box_tests += w.box_tests;
      work->triangle_tests += w.triangle_tests;
      work->lookups += w.lookups;
      work->box_tests_in_ls += w.box_tests_in_ls;
      work->triangle_tests_in_ls += w.triangle_tests_in_ls;
    }
}

}  // namespace

void trace_rays(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters, Traversal traversal, TraceWorkTotals* work,
                const std::vector<uint8_t>* ls_subtrees) {
  trace_chunks(accel, lookup, rays, hits, count, any_hit, false, counters, traversal, work, ls_subtrees);
}

void trace_occlusion(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters,
                     Traversal traversal) {
  trace_chunks(accel, lookup, rays, hits, count, true, true, counters, traversal, nullptr, nullptr);
}

void trace_occlusion(const Accel& accel, const LsLookup& lookup, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters) {
  trace_occlusion(accel, lookup, rays, hits, count, counters, accel.traversal);
}

}  // namespace ls
