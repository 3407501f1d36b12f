// `bench`: MRays/s of each structure, by the fast path (wide SIMD BVH, the default) and by the scalar
// reference, and of Embree 3 on the very same rays, in one run, on all threads, with ratios.  Each is
// timed `repeats` times, round-robin so that machine noise falls on all alike, and the median is
// reported.
#pragma once

#include "common/base/system_info.h"
#include "common/kernels/layouts.h"
#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/structure/accel.h"

#include <string>
#include <vector>

namespace ls {

struct BenchEntry {
  std::string structure;    // canonical name, or "embree"
  double mrays_per_s = 0.0;  // the fast path (what trace_rays does by default)
  double ratio_vs_embree = 0.0;
  size_t bytes = 0;          // the structure's std430 arrays (Embree: its memory monitor)
  double build_seconds = 0.0;
  // Ours only (0 for Embree):
  double reference_mrays_per_s = 0.0;   // the scalar reference path on the same rays
  double reference_ratio_vs_embree = 0.0;
  double ratio_vs_fast_bvh = 0.0;       // fast path vs our exact fast F-BVH (0 when bvh is not benched)
  size_t bytes_wide = 0;                // the fast path's wide nodes, on top of `bytes`
};

struct BenchResult {
  size_t rays = 0;
  int threads = 0;
  int repeats = 0;
  std::string cpu;          // CPU model from /proc/cpuinfo
  std::string isa;          // the fast path's SIMD instruction set
  std::string embree_isa;   // the one Embree ran (embree_effective_isa)
  int exact_width = 0;
  bool any_hit = false;
  std::vector<BenchEntry> results;  // the structures in the order asked, Embree last
  // embree_disagreement (embree_tracer.h) against the first exact structure benched, named here;
  // empty and NaN when none is.
  std::string embree_compared_with;
  double embree_disagreement = 0.0;
};

// any_hit: occlusion queries (rtcOccluded1 for Embree), e.g. for shadow rays.  Rays outside Embree's
// domain (embree_ray_domain_error) are an InputError: Embree would abort on them.  embree_isa: one of
// embree_isa_names() (embree_tracer.h).
BenchResult run_bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& structures,
                      int repeats, const AccelOptions& options = {}, const LsLookup& lookup = {}, bool any_hit = false,
                      const std::string& embree_isa = "best");

}  // namespace ls
