#include "path_tracer.h"

#include "interrupt.h"
#include "kernels/sampling.h"
#include "kernels/scaled_geometry.h"
#include "kernels/throughput_switch.h"
#include "parallel.h"
#include "surface.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace ls {

LightSet::LightSet(const Scene& scene, const SurfaceLookup& surfaces) : unit_k(lsk::unit_exponent(surfaces.scene_scale())) {
  std::vector<double> power;
  for (uint32_t i = 0; i < scene.instances.size(); ++i) {
    const Mesh& mesh = scene.meshes[scene.instances[i].mesh];
    for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::vec3 e = scene.materials[mesh.materials[t]].emission;
      if (lsk::luminance(e) <= 0.0f) continue;
      lsk::ShadeLight l{};
      surfaces.world_triangle(i, t, l.a, l.b, l.c);
      l.emission = e;
      l.area = lsk::triangle_area_scaled(l.a, l.b, l.c, unit_k, l.normal);
      if (!(l.area > 0.0f) || !std::isfinite(l.area)) continue;
      lights.push_back(l);
      power.push_back(double(l.area) * lsk::luminance(e));
    }
  }
  double sum = 0.0;
  for (double p : power) sum += p;
  double run = 0.0;
  for (double p : power) {
    run += p;
    cdf.push_back(float(run / sum));
  }
  if (!cdf.empty()) cdf.back() = 1.0f;
  total_power = float(sum);
}

void average_passes(RenderResult& result, int spp) {
  const size_t pixels = size_t(result.width) * result.height;
  const float inv_spp = 1.0f / float(std::max(1, spp));
  result.total.assign(pixels, glm::vec3(0.0f));
  for (auto& img : result.bounce_images)
    for (size_t p = 0; p < pixels; ++p) img[p] *= inv_spp;
  // The total adds finite bounce images; one whose sum passes the float range keeps the largest
  // float instead (and is counted with the dropped samples): no image ever holds Inf or NaN.
  for (size_t p = 0; p < pixels; ++p) {
    glm::dvec3 sum(0.0);
    for (const auto& img : result.bounce_images) sum += glm::dvec3(img[p]);
    const glm::dvec3 clamped = glm::min(sum, glm::dvec3(double(std::numeric_limits<float>::max())));
    result.total[p] = glm::vec3(clamped);
    if (clamped != sum) ++result.dropped_samples;
  }
}

lsk::ShadeContext shade_context(const SurfaceLookup& surfaces, const LightSet& lights, const RenderOptions& options) {
  lsk::ShadeContext c = surfaces.context();
  c.lights = lights.lights.data();
  c.light_cdf = lights.cdf.data();
  c.shade.seed = options.seed;
  c.shade.light_count = uint32_t(lights.lights.size());
  c.shade.total_power = lights.total_power;
  c.shade.bounces = uint32_t(std::max(0, options.bounces));
  c.shade.unit_k = lights.unit_k;
  return c;
}

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

std::vector<uint32_t> render_pixels(const RenderOptions& options) {
  const uint32_t pixels = options.width * options.height;
  if (options.pixels.empty()) {
    std::vector<uint32_t> all(pixels);
    for (uint32_t p = 0; p < pixels; ++p) all[p] = p;
    return all;
  }
  for (size_t i = 0; i < options.pixels.size(); ++i)
    if (options.pixels[i] >= pixels || (i > 0 && options.pixels[i] <= options.pixels[i - 1]))
      throw InputError("render: the pixels to render must be ascending indices into the image");
  return options.pixels;
}

uint64_t RenderResult::indirect_rays() const {
  uint64_t n = 0;
  for (size_t k = 1; k < bounces.size(); ++k) n += bounces[k].extension_rays + bounces[k].shadow_rays;
  return n;
}

double RenderResult::indirect_seconds() const {
  double s = 0.0;
  for (size_t k = 1; k < bounces.size(); ++k) s += bounces[k].trace_seconds;
  return s;
}

double RenderResult::indirect_mrays_per_s() const {
  const double s = indirect_seconds();
  return s > 0.0 ? double(indirect_rays()) / s * 1e-6 : 0.0;
}

std::map<std::string, Accel> build_schedule_structures(const Scene& scene, const Schedule& schedule,
                                                       const AccelOptions& options, const ThroughputSwitch& throughput_switch) {
  std::map<std::string, Accel> built;
  for (const StructureSpec& spec : schedule.per_bounce)
    if (!built.count(spec.name())) built.emplace(spec.name(), build_accel(scene, spec, options));
  if (throughput_switch.enabled() && !built.count(throughput_switch.structure.name()))
    built.emplace(throughput_switch.structure.name(), build_accel(scene, throughput_switch.structure, options));
  return built;
}

std::vector<StructureSpec> render_structures(const RenderOptions& options) {
  std::vector<StructureSpec> specs;
  auto add = [&](const StructureSpec& spec) {
    for (const StructureSpec& s : specs)
      if (s == spec) return;
    specs.push_back(spec);
  };
  for (int k = 0; k <= options.bounces; ++k) add(options.schedule.at(k));
  if (options.throughput_switch.enabled()) add(options.throughput_switch.structure);
  return specs;
}

RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                    const Progress& progress, const BatchTracer& tracer) {
  // Each structure's own traversal (accel.traversal); shadow rays (any hit) are occlusion queries,
  // of which the render reads only whether they are blocked.
  const BatchTracer trace_batch =
      tracer ? tracer
             : BatchTracer([](const Accel& a, const lsk::Ray* r, lsk::Hit* h, size_t n, bool any, lsk::LsCounters* c) {
                 if (any)
                   trace_occlusion(a, r, h, n, c);
                 else
                   trace_rays(a, r, h, n, any, c);
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
    const uint32_t sample = uint32_t(s);
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
