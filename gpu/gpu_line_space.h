// The Line Space candidate search on the GPU (shaders/ls_candidates.comp): every shaft of every LS
// node, with the CPU builder's layout (layout_line_space) and packing rule (pack_ls_candidates), so the
// candidate array equals the CPU's bit for bit.
#pragma once

#include "common/structure/accel.h"
#include "gpu/vk_context.h"

namespace ls::gpu {

struct GpuSearchTiming {
  double kernel_seconds = 0.0;  // timestamp queries, summed over the dispatches
  double wall_seconds = 0.0;    // the whole search: upload, dispatches, read-back, packing
};

// Fills accel.ls_candidates of a structure laid out without a search (AccelOptions::search_candidates
// = false) and sets accel.ls_info.empty_shafts and .seconds (the wall time of the search).
void search_candidates_gpu(const VulkanContext& context, Accel& accel, GpuSearchTiming* timing = nullptr);

// build_accel() with the candidate search on the GPU.  build_seconds includes it.
Accel build_accel_gpu(const VulkanContext& context, const Scene& scene, const StructureSpec& spec,
                      const AccelOptions& options = {}, GpuSearchTiming* timing = nullptr);

}  // namespace ls::gpu
