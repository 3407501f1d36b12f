#include "bench.h"

#include "accel.h"
#include "embree_tracer.h"

#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>

namespace ls {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  return "unknown CPU";
}

BenchResult run_bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& structures,
                      int repeats, const AccelOptions& options) {
  BenchResult result;
  result.rays = rays.size();
  result.threads = tbb::info::default_concurrency();
  result.repeats = std::max(1, repeats);
  result.cpu = cpu_model();

  std::vector<Accel> built;
  for (const StructureSpec& spec : structures) built.push_back(build_accel(scene, spec, options));
  EmbreeTracer embree(scene);

  std::vector<lsk::Hit> hits(rays.size());
  std::vector<std::function<void()>> runs;
  for (const Accel& accel : built)
    runs.push_back([&] { trace_rays(accel, rays.data(), hits.data(), rays.size(), false); });
  runs.push_back([&] { embree.trace(rays.data(), hits.data(), rays.size(), false); });

  std::vector<std::vector<double>> seconds(runs.size());
  for (auto& run : runs) run();  // warm caches and thread pools once
  for (int r = 0; r < result.repeats; ++r)
    for (size_t i = 0; i < runs.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      runs[i]();
      seconds[i].push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  for (size_t i = 0; i < runs.size(); ++i) {
    BenchEntry e;
    const bool is_embree = i == built.size();
    e.structure = is_embree ? "embree" : built[i].spec.name();
    e.mrays_per_s = double(rays.size()) / median(seconds[i]) * 1e-6;
    e.bytes = is_embree ? embree.bytes() : built[i].bytes_total();
    e.build_seconds = is_embree ? embree.build_seconds() : built[i].build_seconds;
    result.results.push_back(e);
  }
  const double embree_speed = result.results.back().mrays_per_s;
  for (BenchEntry& e : result.results) e.ratio_vs_embree = embree_speed > 0.0 ? e.mrays_per_s / embree_speed : 0.0;
  return result;
}

}  // namespace ls
