#include "cpu/app/cpu_backend.h"

#include "common/render/backend.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"
#include "cpu/app/bench.h"
#include "cpu/app/cli_report.h"
#include "cpu/build/build_structures.h"
#include "cpu/build/top_level_update.h"
#include "cpu/render/path_tracer.h"
#include "cpu/trace/trace_rays.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>

namespace ls {
namespace {

void print_bench(const BenchResult& r, bool json) {
  if (json) {
    nlohmann::json results = nlohmann::json::array();
    for (const BenchEntry& e : r.results) {
      nlohmann::json j{{"structure", e.structure},
                       {"mrays_per_s", e.mrays_per_s},
                       {"ratio_vs_embree", e.ratio_vs_embree},
                       {"bytes", e.bytes},
                       {"build_seconds", e.build_seconds}};
      if (e.structure != "embree") {
        j["traversal"] = "fast";
        j["reference_mrays_per_s"] = e.reference_mrays_per_s;
        j["reference_ratio_vs_embree"] = e.reference_ratio_vs_embree;
        j["ratio_vs_fast_bvh"] = e.ratio_vs_fast_bvh > 0.0 ? nlohmann::json(e.ratio_vs_fast_bvh) : nlohmann::json();
        j["bytes_wide"] = e.bytes_wide;
      }
      results.push_back(j);
    }
    std::cout << nlohmann::json{{"rays", r.rays}, {"threads", r.threads}, {"repeats", r.repeats}, {"device", "cpu: " + r.cpu},
                                {"isa", r.isa}, {"embree_isa", r.embree_isa}, {"exact_width", r.exact_width}, {"any_hit", r.any_hit},
                                {"embree_compared_with", r.embree_compared_with.empty() ? nlohmann::json() : nlohmann::json(r.embree_compared_with)},
                                {"embree_disagreement", std::isnan(r.embree_disagreement) ? nlohmann::json() : nlohmann::json(r.embree_disagreement)},
                                {"results", results}}
                     .dump(2)
              << "\n";
    return;
  }
  std::printf("%zu rays (%s), %d thread%s, median of %d runs, %s\n", r.rays,
              r.any_hit ? "occlusion: fast path and Embree; any hit: reference" : "closest hit",
              r.threads, r.threads == 1 ? "" : "s", r.repeats, r.cpu.c_str());
  std::printf("fast path: %d-wide order-free BVH, %s; reference: the scalar single-source kernels; Embree: %s\n", r.exact_width,
              r.isa.c_str(), r.embree_isa.c_str());
  std::printf("%-14s %10s %10s %10s %10s %9s %10s %9s %9s\n", "structure", "fast MR/s", "vs Embree", "vs bvh", "ref MR/s",
              "ref vs E", "fast/ref", "MB", "build ms");
  for (const BenchEntry& e : r.results) {
    if (e.structure == "embree") {
      std::printf("%-14s %10.2f %9.2fx %10s %10s %9s %10s %9.2f %9.2f\n", e.structure.c_str(), e.mrays_per_s,
                  e.ratio_vs_embree, "", "", "", "", double(e.bytes) / 1e6, e.build_seconds * 1e3);
      continue;
    }
    char vs_bvh[16] = "-";  // no bvh in the run
    if (e.ratio_vs_fast_bvh > 0.0) std::snprintf(vs_bvh, sizeof(vs_bvh), "%.2fx", e.ratio_vs_fast_bvh);
    std::printf("%-14s %10.2f %9.2fx %10s %10.2f %8.2fx %9.2fx %9.2f %9.2f\n", e.structure.c_str(), e.mrays_per_s,
                e.ratio_vs_embree, vs_bvh, e.reference_mrays_per_s, e.reference_ratio_vs_embree,
                e.reference_mrays_per_s > 0.0 ? e.mrays_per_s / e.reference_mrays_per_s : 0.0,
                double(e.bytes + e.bytes_wide) / 1e6, e.build_seconds * 1e3);
  }
  // Embree answering otherwise times other work: it drops triangles past +-1.844e18 and misses at tiny scales.
  if (!std::isnan(r.embree_disagreement) && r.embree_disagreement > 1e-3)
    std::printf("warning: Embree's hits differ from %s's on %.1f %% of the rays (a hit against a miss, or t 1e-3 apart): "
                "its MRays/s are not of the same work\n",
                r.embree_compared_with.c_str(), 100.0 * r.embree_disagreement);
}

class CpuBackend : public Backend {
 public:
  std::string device() const override { return ""; }
  Accel build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) override {
    return build_planned_accel(scene, spec, options);
  }
  void print_build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options, bool json) override {
    ls::print_build(build_planned_accel(scene, spec, options), json);
  }
  // With --traversal reference the log line adds the kernels' work counts (the 2l-ls:auto work model
  // is fitted to them: docs/performance.md, "Per-object Line Space under a memory budget").
  std::vector<lsk::Hit> trace(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays, bool any_hit,
                              lsk::LsCounters* counters, std::string* note) override {
    std::vector<lsk::Hit> hits(rays.size());
    TraceWorkTotals work;
    const bool reference = accel.traversal == Traversal::Reference;
    const std::vector<uint8_t> ls_subtrees = reference ? line_space_subtrees(accel) : std::vector<uint8_t>();
    trace_rays(accel, lookup, rays.data(), hits.data(), rays.size(), any_hit, counters, accel.traversal, reference ? &work : nullptr,
               &ls_subtrees);
    if (reference && note) {
      *note = "; reference work: " + std::to_string(work.box_tests) + " box tests, " + std::to_string(work.triangle_tests) +
              " triangle tests, " + std::to_string(work.lookups) + " lookups";
      if (accel.spec.line_space())
        *note += " (below the Line Space nodes: " + std::to_string(work.box_tests_in_ls) + " box tests, " +
                 std::to_string(work.triangle_tests_in_ls) + " triangle tests)";
    }
    return hits;
  }
  RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                      const Progress& progress) override {
    return ls::render(scene, structures, options, progress);
  }
  void bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& specs, int repeats,
             const AccelOptions& options, const LsLookup& lookup, bool any_hit, const std::string& embree_isa,
             bool json) override {
    print_bench(run_bench(scene, rays, specs, repeats, options, lookup, any_hit, embree_isa), json);
  }
  TopLevelUpdate update_top_level(const Scene& posed, Accel& accel, TopLevelMode mode) override {
    return ls::update_top_level(posed, accel, mode);
  }
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend() { return std::make_unique<CpuBackend>(); }

}  // namespace ls
