#include "cpu/app/bench.h"

#include "common/base/memory_budget.h"
#include "common/base/system_info.h"
#include "common/base/thread_limit.h"
#include "common/structure/accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/trace/embree_tracer.h"
#include "cpu/trace/fast_tracer.h"
#include "cpu/trace/trace_rays.h"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>

namespace ls {

BenchResult run_bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& structures,
                      int repeats, const AccelOptions& options, const LsLookup& lookup, bool any_hit, const std::string& embree_isa) {
  BenchResult result;
  result.rays = rays.size();
  result.threads = thread_count();
  result.repeats = std::max(1, repeats);
  result.cpu = cpu_model();
  result.isa = fast_path_isa();
  result.exact_width = options.exact_width;
  result.any_hit = any_hit;

  const std::string outside = embree_ray_domain_error(rays.data(), rays.size());
  if (!outside.empty()) throw InputError("bench times Embree on the same rays: " + outside);
  // The first exact structure's hits are kept to check Embree's against (it answers as the BVH does).
  const auto exact = std::find_if(structures.begin(), structures.end(), [](const StructureSpec& s) { return !s.line_space(); });
  const size_t compared = size_t(exact - structures.begin());
  const bool compare = exact != structures.end();

  // The rays, the hit arrays, the structures and Embree's scene stay in memory together for the timed
  // runs: each structure, then Embree, is refused over what the ones before it left of the budget
  // (memory_budget.h), so that together they stay within it.
  const size_t budget = memory_budget(options.limits.max_memory);
  size_t held = ray_bytes(rays.size(), false, compare ? 2 : 1);  // then the structures built so far, fast paths included
  check_held_budget("bench: " + std::to_string(rays.size()) + " rays and their hits", held, options.limits.max_memory,
                    "use fewer rays (--count) or raise --max-memory");
  std::vector<Accel> built;
  for (const StructureSpec& spec : structures) {
    const std::string held_by = "bench holds its rays, hits and structures at once, and the rays, hits and structures before '" +
                                spec.name() + "' take " + mib_text(double(held)) + " of the budget of " + mib_budget_text(double(budget)) +
                                ": bench fewer --structures or raise --max-memory";
    if (held >= budget) throw InputError(held_by);
    AccelOptions left = options;
    left.limits.max_memory = budget - held;
    try {
      built.push_back(build_planned_accel(scene, spec, left));
    } catch (const InputError& e) {
      if (held == 0) throw;
      throw InputError(std::string(e.what()) + " (" + held_by + ")");
    }
    held += built.back().bytes_total() + built.back().bytes_wide();
  }
  const std::string embree_held_by = "bench holds Embree's scene beside its rays, hits and structures, which take " +
                                    mib_text(double(held)) + " of the budget of " + mib_budget_text(double(budget)) +
                                    ": bench fewer --structures or raise --max-memory";
  if (held >= budget) throw InputError("no memory is left for Embree's scene (" + embree_held_by + ")");
  std::unique_ptr<EmbreeTracer> made;
  try {
    made = std::make_unique<EmbreeTracer>(scene, embree_isa, budget - held);
  } catch (const EmbreeOverBudget& e) {
    throw InputError(std::string(e.what()) + " (" + embree_held_by + ")");
  }
  const EmbreeTracer& embree = *made;
  result.embree_isa = embree.isa();

  // Runs: per structure the fast path, then the reference; Embree last.
  std::vector<lsk::Hit> hits(rays.size());
  std::vector<std::function<void()>> runs;
  for (const Accel& accel : built) {
    // Occlusion queries (rtcOccluded1's kind) on the fast path; the reference keeps its any hit.
    if (any_hit)
      runs.push_back([&] { trace_occlusion(accel, lookup, rays.data(), hits.data(), rays.size(), nullptr, Traversal::Fast); });
    else
      runs.push_back([&] { trace_rays(accel, lookup, rays.data(), hits.data(), rays.size(), false, nullptr, Traversal::Fast); });
    runs.push_back([&] { trace_rays(accel, lookup, rays.data(), hits.data(), rays.size(), any_hit, nullptr, Traversal::Reference); });
  }
  runs.push_back([&] { embree.trace(rays.data(), hits.data(), rays.size(), any_hit); });

  std::vector<std::vector<double>> seconds(runs.size());
  std::vector<lsk::Hit> exact_hits;
  for (size_t i = 0; i < runs.size(); ++i) {  // warm caches and thread pools once
    runs[i]();
    if (compare && i == 2 * compared) exact_hits = hits;  // its fast path
  }
  result.embree_compared_with = compare ? exact->name() : "";
  result.embree_disagreement =
      compare ? embree_disagreement(hits.data(), exact_hits.data(), rays.size(), any_hit) : std::numeric_limits<double>::quiet_NaN();
  exact_hits = {};
  for (int r = 0; r < result.repeats; ++r)
    for (size_t i = 0; i < runs.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      runs[i]();
      seconds[i].push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  auto mrays = [&](size_t run) {
    std::vector<double> v = seconds[run];
    std::sort(v.begin(), v.end());
    return double(rays.size()) / v[v.size() / 2] * 1e-6;
  };
  for (size_t i = 0; i < built.size(); ++i) {
    BenchEntry e;
    e.structure = built[i].spec.name();
    e.mrays_per_s = mrays(2 * i);
    e.reference_mrays_per_s = mrays(2 * i + 1);
    e.bytes = built[i].bytes_total();
    e.bytes_wide = built[i].bytes_wide();
    e.build_seconds = built[i].build_seconds;
    result.results.push_back(e);
  }
  BenchEntry em;
  em.structure = "embree";
  em.mrays_per_s = mrays(runs.size() - 1);
  em.bytes = embree.bytes();
  em.build_seconds = embree.build_seconds();
  result.results.push_back(em);

  const double embree_speed = em.mrays_per_s;
  double fast_bvh = 0.0;
  for (const BenchEntry& e : result.results)
    if (e.structure == "bvh") fast_bvh = e.mrays_per_s;
  for (BenchEntry& e : result.results) {
    e.ratio_vs_embree = embree_speed > 0.0 ? e.mrays_per_s / embree_speed : 0.0;
    if (e.structure == "embree") continue;
    e.reference_ratio_vs_embree = embree_speed > 0.0 ? e.reference_mrays_per_s / embree_speed : 0.0;
    e.ratio_vs_fast_bvh = fast_bvh > 0.0 ? e.mrays_per_s / fast_bvh : 0.0;
  }
  return result;
}

}  // namespace ls
