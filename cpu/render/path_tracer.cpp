#include "cpu/render/path_tracer.h"

#include "common/base/interrupt.h"
#include "common/base/parallel.h"
#include "common/kernels/sampling.h"
#include "common/kernels/scaled_geometry.h"
#include "common/kernels/throughput_switch.h"
#include "common/render/light_set.h"
#include "common/render/render_types.h"
#include "common/render/surface.h"
#include "common/structure/accel.h"
#include "cpu/trace/trace_rays.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace ls {

namespace {

// The throughput switch's structure as the render loop uses it (accel null: the switch is off).
struct SwitchedTracing {
  const Accel* accel = nullptr;
  float threshold = 0.0f;
};

SwitchedTracing switched_tracing(const std::map<std::string, Accel>& structures, const ThroughputSwitch& s) {
  SwitchedTracing t;
  if (!s.enabled()) return t;
  const auto it = structures.find(s.structure.name());
  if (it == structures.end()) throw InputError("render: structure '" + s.structure.name() + "' was not built");
  t.accel = &it->second;
  t.threshold = s.threshold;
  return t;
}

// Orders `active` as the paths that follow the schedule, then those switched at this bounce (both in
// pixel order); returns how many follow the schedule.
size_t partition_switched(std::vector<uint32_t>& active, const std::vector<lsk::PathState>& paths) {
  return size_t(std::stable_partition(active.begin(), active.end(), [&](uint32_t p) { return paths[p].switched == 0u; }) -
                active.begin());
}

void add_switched(BounceStats& stats, const lsk::LsCounters& counters, double seconds) {
  stats.trace_seconds += seconds;
  stats.switched_seconds += seconds;
  add_counters(stats.ls, counters);
  add_counters(stats.switched_ls, counters);
}

template <typename F>
double timed(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                    const Progress& progress, const BatchTracer& tracer) {
  // Each structure's own traversal (accel.traversal); shadow rays (any hit) are occlusion queries,
  // of which the render reads only whether they are blocked.
  const BatchTracer trace_batch =
      tracer ? tracer
             : BatchTracer([&options](const Accel& a, const lsk::Ray* r, lsk::Hit* h, size_t n, bool any, lsk::LsCounters* c) {
                 if (any)
                   trace_occlusion(a, options.lookup, r, h, n, c);
                 else
                   trace_rays(a, options.lookup, r, h, n, any, c);
               });
  const auto start = std::chrono::steady_clock::now();
  const uint32_t pixels = options.width * options.height;
  const int bounces = options.bounces;
  const SurfaceLookup surfaces(scene);
  const LightSet lights(scene, surfaces);
  const lsk::CameraFrame cam = camera_frame(scene.camera, options.width, options.height);
  lsk::ShadeContext shading = shade_context(surfaces, lights, options);  // read only; its kernels are non-const members

  std::vector<const Accel*> accel(size_t(bounces) + 1);
  RenderResult result;
  result.width = options.width;
  result.height = options.height;
  result.bounces.resize(size_t(bounces) + 1);
  result.bounce_images.assign(size_t(bounces) + 1, std::vector<glm::vec3>(pixels, glm::vec3(0.0f)));
  for (int k = 0; k <= bounces; ++k) {
    const std::string name = options.schedule.at(k).name();
    const auto it = structures.find(name);
    if (it == structures.end()) throw InputError("render: structure '" + name + "' was not built");
    accel[size_t(k)] = &it->second;
    result.bounces[size_t(k)].structure = name;
  }
  const SwitchedTracing switched = switched_tracing(structures, options.throughput_switch);

  const std::vector<uint32_t> order = render_pixels(options);  // the pixels this render computes
  std::vector<lsk::PathState> paths(pixels);
  std::vector<lsk::Hit> hits(pixels);
  std::vector<uint32_t> active;
  std::vector<lsk::Ray> batch;
  std::vector<lsk::Hit> batch_hits;
  std::vector<uint32_t> dropped(pixels, 0);

  for (int s = 0; s < options.spp; ++s) {
    throw_if_interrupted();  // between passes and bounces: Ctrl-C stops within one batch
    const uint32_t sample = options.first_sample + uint32_t(s);
    ls::parallel_for(size_t(0), order.size(), [&](size_t i) { shading.start_path(order[i], sample, cam, paths[order[i]]); });

    for (int k = 0; k <= bounces; ++k) {
      throw_if_interrupted();
      const uint32_t bounce = uint32_t(k);
      const Accel& structure = *accel[size_t(k)];
      BounceStats& stats = result.bounces[size_t(k)];
      std::vector<glm::vec3>& image = result.bounce_images[size_t(k)];

      // Gathers the rays of the selected pixels into one batch and traces it, timed; `active` lists
      // the pixels in batch order.  With the throughput switch on, the switched paths' rays come last
      // and are traced as a second batch with the switch's structure.
      auto trace_selected = [&](auto selected, auto ray_of, bool any_hit, uint64_t& switched_rays) {
        active.clear();
        for (uint32_t p : order)
          if (selected(p)) active.push_back(p);
        const size_t kept = switched.accel ? partition_switched(active, paths) : active.size();
        batch.resize(active.size());
        batch_hits.resize(active.size());
        for (size_t i = 0; i < active.size(); ++i) batch[i] = ray_of(active[i]);
        stats.trace_seconds += timed([&] { trace_batch(structure, batch.data(), batch_hits.data(), kept, any_hit, &stats.ls); });
        if (kept < active.size()) {
          lsk::LsCounters counters{};
          const double seconds = timed([&] {
            trace_batch(*switched.accel, batch.data() + kept, batch_hits.data() + kept, active.size() - kept, any_hit, &counters);
          });
          add_switched(stats, counters, seconds);
          switched_rays += active.size() - kept;
        }
        return uint64_t(active.size());
      };

      // Decide which paths switch structure at this bounce (the kernel's rule, as on the GPU).
      if (switched.accel)
        ls::parallel_for(size_t(0), order.size(), [&](size_t i) {
          lsk::PathState& path = paths[order[i]];
          if (path.alive != 0) path.switched = lsk::throughput_switched(path.throughput, switched.threshold);
        });
      // Trace the extension rays of this bounce (the camera rays at bounce 0).
      stats.extension_rays += trace_selected([&](uint32_t p) { return paths[p].alive != 0; },
                                             [&](uint32_t p) { return paths[p].ray; }, false, stats.switched_extension_rays);
      if (active.empty()) break;

      // Shade: emission found, a light sample for next-event estimation, the next direction.
      ls::parallel_for(size_t(0), active.size(), [&](size_t i) {
        const uint32_t p = active[i];
        shading.shade_path(p, sample, bounce, batch_hits[i], paths[p], image[p], dropped[p]);
      });

      // Trace this bounce's shadow rays (any hit) and add the light they let through.
      stats.shadow_rays += trace_selected([&](uint32_t p) { return paths[p].has_shadow != 0; },
                                          [&](uint32_t p) { return paths[p].shadow_ray; }, true, stats.switched_shadow_rays);
      ls::parallel_for(size_t(0), active.size(), [&](size_t i) {
        if (batch_hits[i].triangle != lsk::LS_INVALID) return;
        const uint32_t p = active[i];
        shading.add_shadow_light(paths[p], image[p], dropped[p]);
      });
    }
    if (progress) progress(s + 1, options.spp);
  }

  average_passes(result, options.spp);
  for (uint32_t d : dropped) result.dropped_samples += d;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace ls
