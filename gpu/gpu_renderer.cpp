#include "gpu/gpu_renderer.h"

#include "common/base/interrupt.h"
#include "common/render/light_set.h"
#include "common/render/render_types.h"
#include "common/render/surface.h"
#include "common/structure/accel.h"
#include "gpu/gpu_line_space.h"
#include "gpu/gpu_trace.h"
#include "gpu/shaders.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <utility>

namespace ls::gpu {
namespace {

constexpr uint32_t kGroup = 64;  // local_size_x of shade.comp

// shade.comp's push constants and constants buffer (common/kernels/layouts.h).
using lsk::ShadeConstants;
using lsk::ShadePush;

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
                        const RenderOptions& options, const Progress& progress,
                        const std::map<const Accel*, const GpuAccel*>* resident) {
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
    const GpuAccel* on_device = nullptr;
    if (resident) {
      const auto r = resident->find(&it->second);
      if (r != resident->end()) on_device = r->second;
    }
    if (!on_device) {
      auto& up = uploaded[&it->second];
      if (!up) up = std::make_unique<GpuAccel>(context, it->second);
      on_device = up.get();
    }
    accel[size_t(k)] = on_device;
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
  // One shade.comp step over `count` entries of a batch (its pixels and hits), appending to the two
  // output lists (next segments and shadow rays; mode 3: the schedule's and the switched rays).
  auto run_shade = [&](ShadePush push, const Buffer& batch_pixels, const Buffer& batch_hits, RayList& out_next,
                       RayList& out_shadow) {
    if (push.count == 0) return;
    shade.bind({&instances, &vertices, &triangles, &materials, &light_buffer, &cdf, &constant_buffer, &paths, &images,
                &dropped, &batch_pixels, &batch_hits, &out_next.rays, &out_next.pixels, &out_shadow.rays,
                &out_shadow.pixels, &counts});
    context.submit_and_wait([&](VkCommandBuffer cmd) { shade.record(cmd, &push, (push.count + kGroup - 1) / kGroup); });
  };
  // Traces a list on the GPU, timed by timestamps around the trace dispatches (wall time without them).
  auto trace_list = [&](int k, const RayList& list, uint32_t count, bool any_hit) {
    if (count == 0) return;
    BounceStats& stats = result.bounces[size_t(k)];
    GpuTraceTiming timing;
    tracer.trace_buffers(*accel[size_t(k)], options.lookup, list.rays, list.hits, count, any_hit, line_space[size_t(k)] ? &stats.ls : nullptr,
                         &timing);
    stats.trace_seconds += timing.kernel_seconds > 0.0 ? timing.kernel_seconds : timing.wall_seconds;
  };
  // The throughput switch (throughput_switch.h): its structure and the two lists a ray list splits into.
  const ThroughputSwitch& policy = options.throughput_switch;
  std::unique_ptr<GpuAccel> switch_accel;
  std::unique_ptr<RayList> kept, switched;
  if (policy.enabled()) {
    const auto it = structures.find(policy.structure.name());
    if (it == structures.end()) throw InputError("render: structure '" + policy.structure.name() + "' was not built");
    switch_accel = std::make_unique<GpuAccel>(context, it->second);
    kept = std::make_unique<RayList>(context, pixels);
    switched = std::make_unique<RayList>(context, pixels);
  }
  auto trace_switched = [&](int k, const RayList& list, uint32_t count, bool any_hit) {
    if (count == 0) return;
    BounceStats& stats = result.bounces[size_t(k)];
    GpuTraceTiming timing;
    lsk::LsCounters counters{};
    tracer.trace_buffers(*switch_accel, options.lookup, list.rays, list.hits, count, any_hit, policy.structure.line_space() ? &counters : nullptr,
                         &timing);
    const double seconds = timing.kernel_seconds > 0.0 ? timing.kernel_seconds : timing.wall_seconds;
    stats.trace_seconds += seconds;
    stats.switched_seconds += seconds;
    add_counters(stats.ls, counters);
    add_counters(stats.switched_ls, counters);
    (any_hit ? stats.switched_shadow_rays : stats.switched_extension_rays) += count;
  };
  // Traces a list of bounce k's rays and returns the lists to shade: itself, or with the switch on its
  // split (shade.comp mode 3, the kernel's decision) into the schedule's rays and the switched ones.
  struct Group {
    const RayList* list;
    uint32_t count;
  };
  auto trace_groups = [&](int k, const RayList& list, uint32_t count, bool any_hit) -> std::vector<Group> {
    if (!policy.enabled()) {
      trace_list(k, list, count, any_hit);
      return {{&list, count}};
    }
    const uint32_t zero[2] = {0, 0};
    counts.upload(zero, sizeof(zero));
    ShadePush split{};
    split.mode = 3;
    split.count = count;
    split.list_kind = any_hit ? 1u : 0u;
    split.switch_threshold = policy.threshold;
    run_shade(split, list.pixels, list.hits, *kept, *switched);
    uint32_t got[2];
    counts.download(got, sizeof(got));
    trace_list(k, *kept, got[0], any_hit);
    trace_switched(k, *switched, got[1], any_hit);
    return {{kept.get(), got[0]}, {switched.get(), got[1]}};
  };

  for (int s = 0; s < options.spp; ++s) {
    throw_if_interrupted();  // between passes and bounces, like the CPU renderer
    ShadePush push{};
    push.sample_index = options.first_sample + uint32_t(s);
    push.mode = 0;
    push.count = uint32_t(order.size());
    run_shade(push, selection, extension.hits, extension, shadow);  // the selected pixels' camera rays into extension's list
    uint32_t extension_count = push.count;
    for (int k = 0; k <= bounces; ++k) {
      throw_if_interrupted();
      BounceStats& stats = result.bounces[size_t(k)];
      stats.extension_rays += extension_count;
      if (extension_count == 0) break;
      const std::vector<Group> traced = trace_groups(k, extension, extension_count, false);
      const uint32_t zero[2] = {0, 0};
      counts.upload(zero, sizeof(zero));
      push.mode = 1;
      push.bounce = uint32_t(k);
      push.image_offset = uint32_t(k) * pixels * 3;
      for (const Group& g : traced) {
        push.count = g.count;
        run_shade(push, g.list->pixels, g.list->hits, next, shadow);
      }
      uint32_t got[2];
      counts.download(got, sizeof(got));
      stats.shadow_rays += got[1];
      push.mode = 2;
      for (const Group& g : trace_groups(k, shadow, got[1], true)) {
        push.count = g.count;
        run_shade(push, g.list->pixels, g.list->hits, next, shadow);
      }
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
