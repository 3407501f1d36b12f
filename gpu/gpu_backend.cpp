#include "gpu/gpu_backend.h"

#include "common/render/backend.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"
#include "cpu/app/cli_report.h"
#include "cpu/build/top_level_update.h"
#include "gpu/gpu_line_space.h"
#include "gpu/gpu_renderer.h"
#include "gpu/gpu_trace.h"
#include "gpu/vk_context.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>

namespace ls::gpu {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

class GpuBackend : public Backend {
 public:
  explicit GpuBackend(const std::string& choice) : context_(choice), device_(context_.description()) {}

  std::string device() const override { return device_; }
  Accel build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) override {
    return build_accel_gpu(context_, scene, spec, options);
  }
  void print_build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options, bool json) override {
    GpuSearchTiming timing;
    const Accel accel = build_accel_gpu(context_, scene, spec, options, &timing);
    ls::print_build(accel, json, device_);
    if (!json && accel.spec.line_space()) {
      const double shafts = double(accel.ls_info.shafts);
      std::printf("gpu search     %.3f s wall, %.3f s kernels: %.3g shafts/s (kernels) on %s\n", timing.wall_seconds,
                  timing.kernel_seconds, timing.kernel_seconds > 0.0 ? shafts / timing.kernel_seconds : 0.0, device_.c_str());
    }
  }
  std::vector<lsk::Hit> trace(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays, bool any_hit,
                              lsk::LsCounters* counters, std::string* timing_text) override {
    GpuAccel uploaded(context_, accel);
    GpuTracer tracer(context_);
    tracer.set_rays(rays);
    GpuTraceTiming timing;
    std::vector<lsk::Hit> hits = tracer.trace(uploaded, lookup, any_hit, counters, &timing);
    if (timing_text) *timing_text = " in " + std::to_string(timing.kernel_seconds) + " s (kernel)";
    return hits;
  }
  // Structures stay on the device between renders (render --frames): a new build is uploaded whole,
  // an updated top level alone.
  RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                      const Progress& progress) override {
    std::map<const Accel*, const GpuAccel*> on_device;
    for (const auto& entry : structures) on_device[&entry.second] = &resident(entry.second);
    return render_gpu(context_, scene, structures, options, progress, &on_device);
  }
  // The top level is rebuilt on the host (as every BVH of the port), then only its nodes and instance
  // records are copied to the device copy, if there is one yet.
  TopLevelUpdate update_top_level(const Scene& posed, Accel& accel, TopLevelMode mode) override {
    const auto start = std::chrono::steady_clock::now();
    TopLevelUpdate update = ls::update_top_level(posed, accel, mode);
    const auto it = resident_.find(&accel);
    if (it != resident_.end() && it->second.build_id == accel.build_id && accel.build_id != 0) {
      it->second.gpu->upload_top_level(accel);
      it->second.top_level_version = accel.top_level_version;
    }
    update.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return update;
  }
  // MRays/s from the median kernel time (timestamps; wall time where the queue has none).
  void bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& specs, int repeats,
             const AccelOptions& options, const LsLookup& lookup, bool any_hit, const std::string& /*embree_isa: no Embree here*/,
             bool json) override {
    struct Entry {
      std::string structure;
      double mrays_per_s = 0.0;
      size_t bytes = 0;
      double build_seconds = 0.0;
    };
    GpuTracer tracer(context_);
    tracer.set_rays(rays);
    std::vector<Entry> results;
    for (const StructureSpec& spec : specs) {
      const Accel accel = build_accel_gpu(context_, scene, spec, options);
      GpuAccel uploaded(context_, accel);
      tracer.trace(uploaded, lookup, any_hit);  // the first dispatch compiles the pipeline on some drivers
      std::vector<double> seconds;
      for (int r = 0; r < repeats; ++r) {
        GpuTraceTiming t;
        tracer.trace(uploaded, lookup, any_hit, nullptr, &t);
        seconds.push_back(t.kernel_seconds > 0.0 ? t.kernel_seconds : t.wall_seconds);
      }
      results.push_back({spec.name(), double(rays.size()) / median(seconds) * 1e-6, accel.bytes_total(), accel.build_seconds});
    }
    if (json) {
      nlohmann::json list = nlohmann::json::array();
      for (const Entry& e : results)
        list.push_back({{"structure", e.structure}, {"mrays_per_s", e.mrays_per_s}, {"bytes", e.bytes},
                        {"build_seconds", e.build_seconds}, {"device", device_}});
      std::cout << nlohmann::json{{"rays", rays.size()}, {"repeats", repeats}, {"any_hit", any_hit}, {"device", device_},
                                  {"results", list}}
                       .dump(2)
                << "\n";
      return;
    }
    std::printf("%zu rays (%s), median of %d runs (kernel time), device %s\n", rays.size(),
                any_hit ? "any hit" : "closest hit", repeats, device_.c_str());
    std::printf("%-14s %12s %12s %10s  %s\n", "structure", "MRays/s", "MB", "build s", "device");
    for (const Entry& e : results)
      std::printf("%-14s %12.2f %12.2f %10.3f  %s\n", e.structure.c_str(), e.mrays_per_s, double(e.bytes) / 1e6,
                  e.build_seconds, device_.c_str());
  }

 private:
  struct Resident {
    std::unique_ptr<GpuAccel> gpu;
    uint64_t build_id = 0;
    uint32_t top_level_version = 0;
  };
  // The device copy of `accel`, made or refreshed as its build id and top-level version say.
  const GpuAccel& resident(const Accel& accel) {
    Resident& r = resident_[&accel];
    if (!r.gpu || accel.build_id == 0 || r.build_id != accel.build_id) {
      r.gpu.reset();  // free the old copy first
      r.gpu = std::make_unique<GpuAccel>(context_, accel);
    } else if (r.top_level_version != accel.top_level_version) {
      r.gpu->upload_top_level(accel);
    }
    r.build_id = accel.build_id;
    r.top_level_version = accel.top_level_version;
    return *r.gpu;
  }

  VulkanContext context_;
  std::string device_;
  std::map<const Accel*, Resident> resident_;
};

}  // namespace

std::unique_ptr<Backend> make_gpu_backend(const std::string& device_choice) { return std::make_unique<GpuBackend>(device_choice); }

}  // namespace ls::gpu
