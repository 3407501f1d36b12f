// `bench`: MRays/s of each structure and of Embree 3 on the very same rays, in one run, on all
// threads, with ratios.  Each is timed `repeats` times, round-robin so that machine noise falls on all
// alike, and the median is reported.
#pragma once

#include "accel.h"
#include "kernels/layouts.h"
#include "scene.h"
#include "structure_name.h"

#include <string>
#include <vector>

namespace ls {

struct BenchEntry {
  std::string structure;    // canonical name, or "embree"
  double mrays_per_s = 0.0;
  double ratio_vs_embree = 0.0;
  size_t bytes = 0;
  double build_seconds = 0.0;
};

struct BenchResult {
  size_t rays = 0;
  int threads = 0;
  int repeats = 0;
  std::string cpu;          // CPU model from /proc/cpuinfo
  std::vector<BenchEntry> results;  // the structures in the order asked, Embree last
};

BenchResult run_bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& structures,
                      int repeats, const AccelOptions& options = {});

std::string cpu_model();

}  // namespace ls
