#include "common/render/light_set.h"

#include "common/kernels/sampling.h"
#include "common/kernels/scaled_geometry.h"
#include "common/render/render_types.h"

#include <cmath>

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

}  // namespace ls
