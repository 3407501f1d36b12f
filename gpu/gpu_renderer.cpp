#include "gpu_renderer.h"

#include "gpu_line_space.h"
#include "gpu_trace.h"
#include "interrupt.h"
#include "shaders.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <utility>

namespace ls::gpu {
namespace {

constexpr uint32_t kGroup = 64;  // local_size_x of shade.comp

// The push constants of shaders/shade.comp (same order).
struct ShadePush {
  uint32_t mode = 0;
  uint32_t sample_index = 0;
  uint32_t bounce = 0;
  uint32_t count = 0;
  uint32_t image_offset = 0;
  uint32_t pad[3] = {0, 0, 0};
};
static_assert(sizeof(ShadePush) == 32, "must match the GLSL push-constant block");

// Binding 6 of shade.comp.
struct ShadeConstants {
  lsk::ShadeParams shade;
  lsk::CameraFrame cam;
};
static_assert(sizeof(ShadeConstants) == 112, "must match the GLSL buffer Constants");

// A list of rays with the pixel each belongs to, and their hits.
struct RayList {
  Buffer rays, pixels, hits;
  RayList(const VulkanContext& context, uint32_t n)
      : rays(context, size_t(n) * sizeof(lsk::Ray), "rays"),
        pixels(context, size_t(n) * sizeof(uint32_t), "pixels"),
        hits(context, size_t(n) * sizeof(lsk::Hit), "hits") {}
};

}  // namespace

RenderResult render_gpu(const VulkanContext& context, const Scene& scene, const std::map<std::string, Accel>& structures,
                        const RenderOptions& options, const Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const uint32_t pixels = options.width * options.height;
  const int bounces = options.bounces;
  const SurfaceLookup surfaces(scene);
  const LightSet lights(scene, surfaces);
  const lsk::ShadeContext shading = shade_context(surfaces, lights, options);

  RenderResult result;
  result.width = options.width;
  result.height = options.height;
  result.bounces.resize(size_t(bounces) + 1);
  result.bounce_images.assign(size_t(bounces) + 1, std::vector<glm::vec3>(pixels, glm::vec3(0.0f)));
  std::vector<const GpuAccel*> accel(size_t(bounces) + 1);
  std::map<const Accel*, std::unique_ptr<GpuAccel>> uploaded;
  std::vector<bool> line_space(size_t(bounces) + 1);
  for (int k = 0; k <= bounces; ++k) {
    const std::string name = options.schedule.at(k).name();
    const auto it = structures.find(name);
    if (it == structures.end()) throw InputError("render: structure '" + name + "' was not built");
    auto& up = uploaded[&it->second];
    if (!up) up = std::make_unique<GpuAccel>(context, it->second);
    accel[size_t(k)] = up.get();
    line_space[size_t(k)] = it->second.spec.line_space();
    result.bounces[size_t(k)].structure = name;
  }

  // The shading kernel's buffers: the scene's arrays, the render's constants, the wavefront's state.
  const Buffer instances = make_buffer(context, surfaces.shade_instances(), "shade_instances");
  const Buffer vertices = make_buffer(context, surfaces.shade_vertices(), "shade_vertices");
  const Buffer triangles = make_buffer(context, surfaces.shade_triangles(), "shade_triangles");
  const Buffer materials = make_buffer(context, surfaces.shade_materials(), "materials");
  const Buffer light_buffer = make_buffer(context, lights.lights, "lights");
  const Buffer cdf = make_buffer(context, lights.cdf, "light_cdf");
  ShadeConstants constants{};
  constants.shade = shading.shade;
  constants.cam = camera_frame(scene.camera, options.width, options.height);
  const Buffer constant_buffer = make_buffer(context, std::vector<ShadeConstants>{constants}, "constants");
  const std::vector<uint32_t> order = render_pixels(options);  // the pixels this render computes
  const Buffer selection = make_buffer(context, order, "selection");
  const Buffer paths(context, size_t(pixels) * sizeof(lsk::PathState), "paths");
  Buffer images(context, size_t(bounces + 1) * pixels * 3 * sizeof(float), "images");
  Buffer dropped(context, size_t(pixels) * sizeof(uint32_t), "dropped");
  std::memset(images.data(), 0, images.size());
  std::memset(dropped.data(), 0, dropped.size());
  RayList extension(context, pixels), next(context, pixels), shadow(context, pixels);
  Buffer counts(context, 2 * sizeof(uint32_t), "counts");

  ComputePipeline shade(context, spirv_shade(), 17, sizeof(ShadePush));
  GpuTracer tracer(context);
  // One shade.comp step over `count` entries of a batch (its pixels and hits), appending to next/shadow.
  auto run_shade = [&](ShadePush push, const Buffer& batch_pixels, const Buffer& batch_hits, RayList& out_next) {
    if (push.count == 0) return;
    shade.bind({&instances, &vertices, &triangles, &materials, &light_buffer, &cdf, &constant_buffer, &paths, &images,
                &dropped, &batch_pixels, &batch_hits, &out_next.rays, &out_next.pixels, &shadow.rays, &shadow.pixels,
                &counts});
    context.submit_and_wait([&](VkCommandBuffer cmd) { shade.record(cmd, &push, (push.count + kGroup - 1) / kGroup); });
  };
  // Traces a list on the GPU, timed by timestamps around the trace dispatches (wall time without them).
  auto trace_list = [&](int k, const RayList& list, uint32_t count, bool any_hit) {
    if (count == 0) return;
    BounceStats& stats = result.bounces[size_t(k)];
    GpuTraceTiming timing;
    tracer.trace_buffers(*accel[size_t(k)], list.rays, list.hits, count, any_hit, line_space[size_t(k)] ? &stats.ls : nullptr,
                         &timing);
    stats.trace_seconds += timing.kernel_seconds > 0.0 ? timing.kernel_seconds : timing.wall_seconds;
  };

  for (int s = 0; s < options.spp; ++s) {
    throw_if_interrupted();  // between passes and bounces, like the CPU renderer
    ShadePush push;
    push.sample_index = uint32_t(s);
    push.mode = 0;
    push.count = uint32_t(order.size());
    run_shade(push, selection, extension.hits, extension);  // the selected pixels' camera rays into extension's list
    uint32_t extension_count = push.count;
    for (int k = 0; k <= bounces; ++k) {
      throw_if_interrupted();
      BounceStats& stats = result.bounces[size_t(k)];
      stats.extension_rays += extension_count;
      if (extension_count == 0) break;
      trace_list(k, extension, extension_count, false);
      const uint32_t zero[2] = {0, 0};
      counts.upload(zero, sizeof(zero));
      push.mode = 1;
      push.bounce = uint32_t(k);
      push.count = extension_count;
      push.image_offset = uint32_t(k) * pixels * 3;
      run_shade(push, extension.pixels, extension.hits, next);
      uint32_t got[2];
      counts.download(got, sizeof(got));
      stats.shadow_rays += got[1];
      trace_list(k, shadow, got[1], true);
      push.mode = 2;
      push.count = got[1];
      run_shade(push, shadow.pixels, shadow.hits, next);
      std::swap(extension, next);
      extension_count = got[0];
    }
    if (progress) progress(s + 1, options.spp);
  }

  std::vector<float> sums(size_t(bounces + 1) * pixels * 3);
  images.download(sums.data(), sums.size() * sizeof(float));
  for (size_t k = 0; k < result.bounce_images.size(); ++k)
    for (uint32_t p = 0; p < pixels; ++p) {
      const float* v = &sums[(k * pixels + p) * 3];
      result.bounce_images[k][p] = glm::vec3(v[0], v[1], v[2]);
    }
  average_passes(result, options.spp);
  std::vector<uint32_t> dropped_counts(pixels);
  dropped.download(dropped_counts.data(), dropped_counts.size() * sizeof(uint32_t));
  for (uint32_t d : dropped_counts) result.dropped_samples += d;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::map<std::string, Accel> build_schedule_structures_gpu(const VulkanContext& context, const Scene& scene,
                                                           const Schedule& schedule, const AccelOptions& options) {
  std::map<std::string, Accel> built;
  for (const StructureSpec& spec : schedule.per_bounce)
    if (!built.count(spec.name())) built.emplace(spec.name(), build_accel_gpu(context, scene, spec, options));
  return built;
}

}  // namespace ls::gpu
