// Tracing a ray buffer on the GPU (shaders/trace.comp): closest or any hit, any of the four
// structures, with the hits and Line Space counters the CPU's ls::trace_rays gives.
#pragma once

#include "gpu/gpu_accel.h"
#include "gpu/vk_pipeline.h"

#include <vector>

namespace ls::gpu {

struct GpuTraceTiming {
  double kernel_seconds = 0.0;  // timestamp queries around the dispatches (0: the queue has none)
  double wall_seconds = 0.0;    // submit to fence, upload and read-back excluded
};

class GpuTracer {
 public:
  explicit GpuTracer(const VulkanContext& context);

  // Uploads the rays (kept for repeated traces of the same rays, e.g. bench).
  void set_rays(const std::vector<lsk::Ray>& rays);
  // Traces the rays set last; hits and counters (added to *counters) as on the CPU.
  std::vector<lsk::Hit> trace(const GpuAccel& accel, const LsLookup& lookup, bool any_hit, lsk::LsCounters* counters = nullptr,
                              GpuTraceTiming* timing = nullptr);
  // Traces the first `count` rays of a device buffer into `hits` (both stay on the device).
  void trace_buffers(const GpuAccel& accel, const LsLookup& lookup, const Buffer& rays, const Buffer& hits, uint32_t count, bool any_hit,
                     lsk::LsCounters* counters = nullptr, GpuTraceTiming* timing = nullptr);

 private:
  const VulkanContext& context_;
  ComputePipeline pipeline_;
  KernelTimer timer_;
  Buffer rays_, hits_, counters_;
  uint32_t count_ = 0;
};

}  // namespace ls::gpu
