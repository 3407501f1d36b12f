#include "gpu/gpu_line_space.h"

#include "common/structure/accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/build/line_space_builder.h"
#include "gpu/gpu_accel.h"
#include "gpu/shaders.h"
#include "gpu/vk_pipeline.h"

#include <algorithm>
#include <chrono>

namespace ls::gpu {
namespace {
constexpr uint32_t kGroup = 64;            // local_size_x of ls_candidates.comp
constexpr size_t kBatchBytes = 64u << 20;  // search results per submission (bounded by the device too)
}  // namespace

void search_candidates_gpu(const VulkanContext& context, Accel& accel, GpuSearchTiming* timing) {
  const auto start = std::chrono::steady_clock::now();
  const size_t ls_count = accel.ls_nodes.size();
  GpuSearchTiming t;
  size_t empty = 0;
  if (ls_count > 0) {
    GpuAccel gpu(context, accel);  // the candidates are not read by the search
    ComputePipeline pipeline(context, spirv_ls_candidates(), 11, sizeof(lsk::ShaderParams));
    KernelTimer timer(context);
    lsk::ShaderParams params = gpu.params(LsLookup{});  // the search asks no Line Space
    params.ls_enabled = 0;
    params.further_rays = uint32_t(accel.ls_options.further_rays);
    params.search_instance = ls_search_instance(accel);
    const size_t limit = std::min<size_t>(kBatchBytes, context.limits().maxStorageBufferRange);
    // With a progress line, at most 1/32 of the nodes a submission, so that it moves (each node's
    // search is its own: the candidates are the same).
    const auto& progress = accel.ls_options.progress;
    const size_t step = progress ? std::max<size_t>(1, (ls_count + 31) / 32) : ls_count;
    size_t done = 0;
    // Consecutive LS nodes of one N share a dispatch (a structure of per-object N has several runs).
    for (size_t run = 0; run < ls_count;) {
      const uint32_t n = accel.ls_nodes[run].n;
      size_t run_end = run;
      while (run_end < ls_count && accel.ls_nodes[run_end].n == n) ++run_end;
      const uint32_t shafts = lsk::ls_shaft_count(n);
      const size_t bytes_per_node = size_t(shafts) * sizeof(uint32_t);
      const size_t batch = std::max<size_t>(
          1, std::min<size_t>({limit / bytes_per_node, run_end - run, context.limits().maxComputeWorkGroupCount[1], step}));
      Buffer prims(context, batch * bytes_per_node, "search results");
      std::vector<const Buffer*> bindings = gpu.bindings();
      bindings.push_back(&prims);
      pipeline.bind(bindings);
      params.ls_n = n;
      std::vector<uint32_t> host(batch * shafts);
      for (size_t first = run; first < run_end; first += batch) {
        params.first_ls = uint32_t(first);
        params.ls_count = uint32_t(std::min(batch, run_end - first));
        context.submit_and_wait([&](VkCommandBuffer cmd) {
          timer.begin(cmd);
          pipeline.record(cmd, &params, (shafts + kGroup - 1) / kGroup, params.ls_count);
          timer.end(cmd);
        });
        t.kernel_seconds += timer.seconds();
        prims.download(host.data(), size_t(params.ls_count) * bytes_per_node);
        for (uint32_t slot = 0; slot < params.ls_count; ++slot)
          empty += pack_ls_candidates(accel, first + slot, host.data() + size_t(slot) * shafts);
        done += params.ls_count;
        if (progress) progress(done, ls_count);
      }
      run = run_end;
    }
  }
  t.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  accel.ls_info.empty_shafts = empty;
  accel.ls_info.seconds = t.wall_seconds;
  if (timing) *timing = t;
}

Accel build_accel_gpu(const VulkanContext& context, const Scene& scene, const StructureSpec& spec, const AccelOptions& options,
                      GpuSearchTiming* timing) {
  AccelOptions laid_out = options;
  laid_out.search_candidates = false;
  laid_out.fast_path = false;  // the device traces with the shared kernels: the CPU's wide trees would be unused
  Accel accel = build_planned_accel(scene, spec, laid_out);
  if (spec.line_space()) {
    search_candidates_gpu(context, accel, timing);
    accel.build_seconds += accel.ls_info.seconds;
  }
  return accel;
}

}  // namespace ls::gpu
