#include "gpu_renderer.h"

#include "gpu_line_space.h"
#include "gpu_trace.h"

#include <algorithm>
#include <memory>

namespace ls::gpu {

RenderResult render_gpu(const VulkanContext& context, const Scene& scene, const std::map<std::string, Accel>& structures,
                        const RenderOptions& options, const Progress& progress) {
  std::map<const Accel*, std::unique_ptr<GpuAccel>> uploaded;
  for (const auto& [name, accel] : structures) uploaded.emplace(&accel, std::make_unique<GpuAccel>(context, accel));
  GpuTracer tracer(context);
  const BatchTracer on_gpu = [&](const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                                 lsk::LsCounters* counters) {
    if (count == 0) return;
    tracer.set_rays(std::vector<lsk::Ray>(rays, rays + count));
    const std::vector<lsk::Hit> out = tracer.trace(*uploaded.at(&accel), any_hit, accel.spec.line_space() ? counters : nullptr);
    std::copy(out.begin(), out.end(), hits);
  };
  return render(scene, structures, options, progress, on_gpu);
}

std::map<std::string, Accel> build_schedule_structures_gpu(const VulkanContext& context, const Scene& scene,
                                                           const Schedule& schedule, const AccelOptions& options) {
  std::map<std::string, Accel> built;
  for (const StructureSpec& spec : schedule.per_bounce)
    if (!built.count(spec.name())) built.emplace(spec.name(), build_accel_gpu(context, scene, spec, options));
  return built;
}

}  // namespace ls::gpu
