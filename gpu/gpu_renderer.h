// The path tracer's wavefront on the GPU: camera rays, tracing, shading (NEE + MIS) and the shadow
// rays' light run in shaders (trace.comp, shade.comp) with the CPU renderer's kernels
// (common/kernels/shade_path.h); the host loops over passes and bounces and reads back the ray counts,
// the images and the trace dispatches' timestamp times.  Same schedules, bounce semantics, random
// numbers and outputs as ls::render (cpu/render/path_tracer.h); on lavapipe the same images bit for bit.
#pragma once

#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "gpu/gpu_accel.h"
#include "gpu/vk_context.h"

#include <map>
#include <string>

namespace ls::gpu {

// resident: structures already on the device (render --frames keeps them between frames and refreshes
// only their top level); the others are uploaded for this render.
RenderResult render_gpu(const VulkanContext& context, const Scene& scene, const std::map<std::string, Accel>& structures,
                        const RenderOptions& options, const Progress& progress = {},
                        const std::map<const Accel*, const GpuAccel*>* resident = nullptr);

// build_schedule_structures() with the Line Space candidates searched on the GPU.
std::map<std::string, Accel> build_schedule_structures_gpu(const VulkanContext& context, const Scene& scene,
                                                           const Schedule& schedule, const AccelOptions& options = {});

}  // namespace ls::gpu
