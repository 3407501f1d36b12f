// The path tracer with every bounce's rays traced on the GPU: the CPU renderer's wavefront
// (cpu/path_tracer.h) with its batches handed to GpuTracer, so schedules, bounce semantics, random
// numbers and outputs are the CPU's by construction.  Shading (NEE + MIS) still runs on the CPU: the
// single-source shading kernel that would move it to the GPU is not written yet (gpu/README.md).
#pragma once

#include "path_tracer.h"
#include "vk_context.h"

#include <map>
#include <string>

namespace ls::gpu {

RenderResult render_gpu(const VulkanContext& context, const Scene& scene, const std::map<std::string, Accel>& structures,
                        const RenderOptions& options, const Progress& progress = {});

// build_schedule_structures() with the Line Space candidates searched on the GPU.
std::map<std::string, Accel> build_schedule_structures_gpu(const VulkanContext& context, const Scene& scene,
                                                           const Schedule& schedule, const AccelOptions& options = {});

}  // namespace ls::gpu
