#include "path_tracer.h"

#include "kernels/camera.h"
#include "kernels/offset_ray.h"
#include "kernels/rng.h"
#include "kernels/sampling.h"
#include "kernels/scaled_geometry.h"
#include "interrupt.h"
#include "surface.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace ls {
namespace {

// Random dimensions used at each bounce.
enum Dim : uint32_t { kPixelX = 0, kPixelY = 1, kLightPick = 2, kLightU = 3, kLightV = 4, kBsdfU = 5, kBsdfV = 6 };

struct Light {
  glm::vec3 a, b, c;
  glm::vec3 normal;  // unit
  glm::vec3 emission;
  float area;        // in scene units (kernels/scaled_geometry.h), like every pdf below
};

// Emissive world triangles with a CDF by power (area x luminance of emission).  Areas, distances
// and densities are in scene units (lengths x 2^unit_k), so they stay finite at 1e20 and 1e-20.
struct LightSet {
  std::vector<Light> lights;
  std::vector<float> cdf;  // inclusive, last == 1
  float total_power = 0.0f;
  int unit_k = 0;

  LightSet(const Scene& scene, const SurfaceLookup& surfaces) : unit_k(lsk::unit_exponent(surfaces.scene_scale())) {
    std::vector<double> power;
    for (uint32_t i = 0; i < scene.instances.size(); ++i) {
      const Mesh& mesh = scene.meshes[scene.instances[i].mesh];
      for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        const glm::vec3 e = scene.materials[mesh.materials[t]].emission;
        if (lsk::luminance(e) <= 0.0f) continue;
        Light l;
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
  bool empty() const { return lights.empty(); }
  size_t pick(float u) const {
    return size_t(std::min<std::ptrdiff_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin(),
                                           std::ptrdiff_t(cdf.size()) - 1));
  }
  // Density, per unit area, of sampling a point on an emissive triangle of emission e.
  float area_pdf(const glm::vec3& e) const { return total_power > 0.0f ? lsk::luminance(e) / total_power : 0.0f; }
};

struct PathState {
  lsk::Ray ray;
  glm::vec3 throughput{1.0f};
  float bsdf_pdf = 0.0f;  // solid-angle density of the direction that made `ray` (MIS)
  bool alive = false;
};

struct ShadowQuery {
  lsk::Ray ray;
  glm::vec3 contribution{0.0f};
  uint32_t pixel = 0;
};

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

template <typename F>
double timed(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

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
                                                       const AccelOptions& options) {
  std::map<std::string, Accel> built;
  for (const StructureSpec& spec : schedule.per_bounce)
    if (!built.count(spec.name())) built.emplace(spec.name(), build_accel(scene, spec, options));
  return built;
}

RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                    const Progress& progress, const BatchTracer& tracer) {
  // The first trace_rays overload: each structure's own traversal (accel.traversal).
  const BatchTracer trace_batch =
      tracer ? tracer
             : BatchTracer([](const Accel& a, const lsk::Ray* r, lsk::Hit* h, size_t n, bool any, lsk::LsCounters* c) {
                 trace_rays(a, r, h, n, any, c);
               });
  const auto start = std::chrono::steady_clock::now();
  const uint32_t pixels = options.width * options.height;
  const int bounces = options.bounces;
  const SurfaceLookup surfaces(scene);
  const LightSet lights(scene, surfaces);
  const lsk::CameraFrame cam = camera_frame(scene.camera, options.width, options.height);
  const float scale = surfaces.scene_scale();

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

  std::vector<PathState> paths(pixels);
  std::vector<lsk::Hit> hits(pixels);
  std::vector<uint32_t> active;
  std::vector<lsk::Ray> batch;
  std::vector<lsk::Hit> batch_hits;
  std::vector<ShadowQuery> shadows(pixels);
  std::vector<char> has_shadow(pixels);
  std::vector<uint32_t> dropped(pixels, 0);

  for (int s = 0; s < options.spp; ++s) {
    throw_if_interrupted();  // between passes and bounces: Ctrl-C stops within one batch
    const uint32_t sample = uint32_t(s);
    tbb::parallel_for(uint32_t(0), pixels, [&](uint32_t p) {
      const float x = float(p % options.width) + lsk::random01(options.seed, p, sample, 0, kPixelX);
      const float y = float(p / options.width) + lsk::random01(options.seed, p, sample, 0, kPixelY);
      paths[p].ray = lsk::camera_ray(cam, x, y);
      paths[p].throughput = glm::vec3(1.0f);
      paths[p].bsdf_pdf = 0.0f;
      paths[p].alive = true;
    });

    for (int k = 0; k <= bounces; ++k) {
      throw_if_interrupted();
      const uint32_t bounce = uint32_t(k);
      const Accel& structure = *accel[size_t(k)];
      BounceStats& stats = result.bounces[size_t(k)];
      std::vector<glm::vec3>& image = result.bounce_images[size_t(k)];

      // Gathers the rays of the selected pixels into one batch and traces it, timed; `active` lists
      // the pixels in batch order.
      auto trace_selected = [&](auto selected, auto ray_of, bool any_hit) {
        active.clear();
        for (uint32_t p = 0; p < pixels; ++p)
          if (selected(p)) active.push_back(p);
        batch.resize(active.size());
        batch_hits.resize(active.size());
        for (size_t i = 0; i < active.size(); ++i) batch[i] = ray_of(active[i]);
        stats.trace_seconds +=
            timed([&] { trace_batch(structure, batch.data(), batch_hits.data(), batch.size(), any_hit, &stats.ls); });
        return uint64_t(active.size());
      };

      // Trace the extension rays of this bounce (the camera rays at bounce 0).
      stats.extension_rays += trace_selected([&](uint32_t p) { return paths[p].alive; },
                                             [&](uint32_t p) { return paths[p].ray; }, false);
      if (active.empty()) break;

      // Shade: emission found, a light sample for next-event estimation, the next direction.
      tbb::parallel_for(size_t(0), active.size(), [&](size_t i) {
        const uint32_t p = active[i];
        PathState& path = paths[p];
        const lsk::Hit& hit = batch_hits[i];
        has_shadow[p] = 0;
        // The sum is what is checked: two huge finite contributions can add up to infinity.
        auto add = [&](const glm::vec3& c) {
          const glm::vec3 sum = image[p] + c;
          if (finite(sum)) image[p] = sum;
          else ++dropped[p];
        };
        if (hit.triangle == lsk::LS_INVALID) {
          add(path.throughput * scene.background);
          path.alive = false;
          return;
        }
        const SurfacePoint sp = surfaces.at(hit, path.ray.dir);
        const Material& mat = scene.materials[sp.material];
        if (lsk::luminance(mat.emission) > 0.0f) {
          float weight = 1.0f;
          if (k > 0) {
            const float dist = lsk::to_scene_units(hit.t * glm::length(path.ray.dir), lights.unit_k);
            const float cos_l = std::fabs(glm::dot(sp.geometric_normal, glm::normalize(path.ray.dir)));
            const float light_pdf = cos_l > 0.0f ? lights.area_pdf(mat.emission) * dist * dist / cos_l : 0.0f;
            weight = lsk::power_heuristic(path.bsdf_pdf, light_pdf);
          }
          add(path.throughput * mat.emission * weight);
        }
        const glm::vec3 n = sp.geometric_normal;
        const glm::vec3 origin = lsk::offset_ray_origin(sp.position, n, scale);
        if (!lights.empty()) {
          const Light& l = lights.lights[lights.pick(lsk::random01(options.seed, p, sample, bounce, kLightPick))];
          const glm::vec3 q = lsk::sample_triangle(l.a, l.b, l.c, lsk::random01(options.seed, p, sample, bounce, kLightU),
                                                   lsk::random01(options.seed, p, sample, bounce, kLightV));
          glm::vec3 nl = l.normal;
          if (glm::dot(nl, origin - q) < 0.0f) nl = -nl;
          const glm::vec3 target = lsk::offset_ray_origin(q, nl, scale);
          const glm::vec3 d = target - origin;
          const glm::vec3 d_units = lsk::to_scene_units(d, lights.unit_k);
          const float dist2 = glm::dot(d_units, d_units);
          const glm::vec3 wi = d_units / std::sqrt(dist2);
          const float cos_s = glm::dot(n, wi);
          const float cos_l = glm::dot(nl, -wi);
          if (cos_s > 0.0f && cos_l > 0.0f && dist2 > 0.0f) {
            const float light_pdf = lights.area_pdf(l.emission) * dist2 / cos_l;
            const float bsdf_pdf = cos_s / lsk::LS_PI;
            // The last bounce traces no further segment to find this light by BSDF sampling, so its
            // light sample carries the whole weight.
            const float weight = k == bounces ? 1.0f : lsk::power_heuristic(light_pdf, bsdf_pdf);
            ShadowQuery& sq = shadows[p];
            sq.ray.origin = origin;
            sq.ray.dir = d;
            sq.ray.tmin = 0.0f;
            sq.ray.tmax = 1.0f;
            sq.contribution = path.throughput * (mat.albedo / lsk::LS_PI) * l.emission * (cos_s * weight / light_pdf);
            sq.pixel = p;
            has_shadow[p] = 1;
          }
        }
        if (k == bounces) {
          path.alive = false;
          return;
        }
        const glm::vec3 dir = lsk::sample_cosine_hemisphere(n, lsk::random01(options.seed, p, sample, bounce, kBsdfU),
                                                            lsk::random01(options.seed, p, sample, bounce, kBsdfV));
        const float cos_o = glm::dot(n, dir);
        if (!(cos_o > 0.0f)) {
          path.alive = false;
          return;
        }
        path.ray.origin = origin;
        path.ray.dir = dir;
        path.ray.tmin = 0.0f;
        path.ray.tmax = lsk::ls_infinity();
        path.bsdf_pdf = cos_o / lsk::LS_PI;
        path.throughput *= mat.albedo;  // albedo/pi * cos / (cos/pi)
        if (!(lsk::luminance(path.throughput) > 0.0f)) path.alive = false;
      });

      // Trace this bounce's shadow rays (any hit) and add the light they let through.
      stats.shadow_rays += trace_selected([&](uint32_t p) { return has_shadow[p] != 0; },
                                          [&](uint32_t p) { return shadows[p].ray; }, true);
      tbb::parallel_for(size_t(0), active.size(), [&](size_t i) {
        if (batch_hits[i].triangle != lsk::LS_INVALID) return;
        const ShadowQuery& sq = shadows[active[i]];
        const glm::vec3 sum = image[sq.pixel] + sq.contribution;
        if (finite(sum)) image[sq.pixel] = sum;
        else ++dropped[sq.pixel];
      });
    }
    if (progress) progress(s + 1, options.spp);
  }

  const float inv_spp = 1.0f / float(std::max(1, options.spp));
  result.total.assign(pixels, glm::vec3(0.0f));
  for (auto& img : result.bounce_images)
    for (uint32_t p = 0; p < pixels; ++p) img[p] *= inv_spp;
  for (uint32_t d : dropped) result.dropped_samples += d;
  // The total adds finite bounce images; one whose sum passes the float range keeps the largest
  // float instead (and is counted with the dropped samples): no image ever holds Inf or NaN.
  for (uint32_t p = 0; p < pixels; ++p) {
    glm::dvec3 sum(0.0);
    for (const auto& img : result.bounce_images) sum += glm::dvec3(img[p]);
    const glm::dvec3 clamped = glm::min(sum, glm::dvec3(double(std::numeric_limits<float>::max())));
    result.total[p] = glm::vec3(clamped);
    if (clamped != sum) ++result.dropped_samples;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace ls
