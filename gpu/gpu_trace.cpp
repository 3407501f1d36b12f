#include "gpu/gpu_trace.h"

#include "gpu/shaders.h"

#include <chrono>

namespace ls::gpu {
namespace {
constexpr uint32_t kGroup = 64;           // local_size_x of trace.comp
constexpr uint32_t kMaxGroups = 65535;    // the minimum maxComputeWorkGroupCount[0] Vulkan guarantees
}  // namespace

GpuTracer::GpuTracer(const VulkanContext& context)
    : context_(context), pipeline_(context, spirv_trace(), 13, sizeof(lsk::ShaderParams)), timer_(context),
      counters_(context, sizeof(lsk::LsCounters)) {}

void GpuTracer::set_rays(const std::vector<lsk::Ray>& rays) {
  if (rays.size() > UINT32_MAX / 2) throw InputError("too many rays for one GPU trace");
  rays_ = make_buffer(context_, rays, "rays");
  hits_ = Buffer(context_, rays.size() * sizeof(lsk::Hit), "hits");
  count_ = uint32_t(rays.size());
}

std::vector<lsk::Hit> GpuTracer::trace(const GpuAccel& accel, const LsLookup& lookup, bool any_hit, lsk::LsCounters* counters,
                                        GpuTraceTiming* timing) {
  trace_buffers(accel, lookup, rays_, hits_, count_, any_hit, counters, timing);
  std::vector<lsk::Hit> hits(count_);
  if (count_) hits_.download(hits.data(), hits.size() * sizeof(lsk::Hit));
  return hits;
}

void GpuTracer::trace_buffers(const GpuAccel& accel, const LsLookup& lookup, const Buffer& rays, const Buffer& hits, uint32_t count, bool any_hit,
                              lsk::LsCounters* counters, GpuTraceTiming* timing) {
  std::vector<const Buffer*> bindings = accel.bindings();
  bindings.push_back(&rays);
  bindings.push_back(&hits);
  bindings.push_back(&counters_);
  pipeline_.bind(bindings);
  const lsk::LsCounters zero{};
  counters_.upload(&zero, sizeof(zero));
  lsk::ShaderParams params = accel.params(lookup);
  params.any_hit = any_hit ? 1u : 0u;
  params.count = count;
  const auto start = std::chrono::steady_clock::now();
  context_.submit_and_wait([&](VkCommandBuffer cmd) {
    timer_.begin(cmd);
    // Dispatches of at most kMaxGroups groups; they write disjoint hits, so no barrier between them.
    for (uint32_t first = 0; first < count; first += kGroup * kMaxGroups) {
      params.first = first;
      const uint32_t n = std::min(count - first, kGroup * kMaxGroups);
      pipeline_.record(cmd, &params, (n + kGroup - 1) / kGroup);
    }
    timer_.end(cmd);
  });
  if (timing) {
    timing->wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    timing->kernel_seconds = timer_.seconds();
  }
  if (counters) {
    lsk::LsCounters got{};
    counters_.download(&got, sizeof(got));
    add_counters(*counters, got);
  }
}

}  // namespace ls::gpu
