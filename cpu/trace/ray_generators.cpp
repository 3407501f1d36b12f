#include "cpu/trace/ray_generators.h"

#include "common/base/parallel.h"
#include "common/kernels/camera.h"
#include "common/kernels/offset_ray.h"
#include "common/kernels/rng.h"
#include "common/kernels/sampling.h"
#include "common/render/surface.h"
#include "common/structure/accel.h"
#include "cpu/trace/trace_rays.h"

namespace ls {

RayKind parse_ray_kind(const std::string& text) {
  if (text == "primary") return RayKind::Primary;
  if (text == "diffuse") return RayKind::Diffuse;
  if (text == "random") return RayKind::Random;
  if (text == "shadow") return RayKind::Shadow;
  throw InputError("unknown ray kind '" + text + "' (expected primary, diffuse, random or shadow)");
}

namespace {

constexpr uint32_t kImageSide = 1024;  // the virtual image primary rays are drawn from

lsk::Ray primary_ray(const lsk::CameraFrame& cam, uint32_t seed, uint32_t index) {
  const float x = lsk::random01(seed, index, 0, 0, 0) * float(kImageSide);
  const float y = lsk::random01(seed, index, 0, 0, 1) * float(kImageSide);
  return lsk::camera_ray(cam, x, y);
}

}  // namespace

std::vector<lsk::Ray> generate_rays(const Scene& scene, const Accel& exact, RayKind kind, size_t count, uint32_t seed) {
  if (kind == RayKind::Shadow) {
    // Segments between the origins of two diffuse rays (surface points, each offset off its surface).
    if (count < 2) throw InputError("shadow rays join the origins of two diffuse rays: --count must be at least 2");
    std::vector<lsk::Ray> rays = generate_rays(scene, exact, RayKind::Diffuse, count, seed);
    std::vector<lsk::Ray> segments(count);
    for (size_t i = 0; i < count; ++i) {
      size_t j = (i + count / 2) % count;
      if (rays[j].origin == rays[i].origin) j = (i + 1) % count;
      // Past that, the next origin that is another point (a zero-length segment is no ray).
      for (size_t tries = 0; rays[j].origin == rays[i].origin && tries < count; ++tries) j = (j + 1) % count;
      if (rays[j].origin == rays[i].origin)
        throw InputError("shadow rays: every diffuse ray of this scene starts at one point, no segment joins two");
      segments[i].origin = rays[i].origin;
      segments[i].tmin = 0.0f;
      segments[i].dir = rays[j].origin - rays[i].origin;
      segments[i].tmax = 1.0f;
    }
    return segments;
  }
  std::vector<lsk::Ray> rays(count);
  const lsk::CameraFrame cam = camera_frame(scene.camera, kImageSide, kImageSide);
  if (kind == RayKind::Primary) {
    ls::parallel_for(size_t(0), count, [&](size_t i) { rays[i] = primary_ray(cam, seed, uint32_t(i)); });
    return rays;
  }
  if (kind == RayKind::Random) {
    const Bounds b = world_bounds(scene);
    ls::parallel_for(size_t(0), count, [&](size_t i) {
      const uint32_t k = uint32_t(i);
      glm::vec3 o;
      for (int a = 0; a < 3; ++a) o[a] = b.lo[a] + (b.hi[a] - b.lo[a]) * lsk::random01(seed, k, 0, 0, uint32_t(a));
      const float z = 1.0f - 2.0f * lsk::random01(seed, k, 0, 0, 3);
      const float phi = 2.0f * lsk::LS_PI * lsk::random01(seed, k, 0, 0, 4);
      const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
      rays[i].origin = o;
      rays[i].tmin = 0.0f;
      rays[i].dir = glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
      rays[i].tmax = lsk::ls_infinity();
    });
    return rays;
  }
  // Diffuse: primary rays that hit something, each followed by one cosine-weighted bounce.  Primary
  // rays are drawn in rounds of `count` candidates until enough hit.
  const SurfaceLookup surfaces(scene);
  const lsk::TraceContext context = trace_context(exact);  // exact: no Line Space to look up
  size_t filled = 0;
  for (uint32_t round = 0; filled < count; ++round) {
    if (round >= 64) throw InputError("diffuse rays: the camera sees (almost) nothing of this scene");
    std::vector<lsk::Ray> candidates(count);
    std::vector<char> ok(count, 0);
    ls::parallel_for(size_t(0), count, [&](size_t i) {
      const uint32_t index = uint32_t(round * count + i);
      const lsk::Ray p = primary_ray(cam, seed, index);
      const lsk::Hit h = trace_ray(context, exact, p, false);
      if (h.triangle == lsk::LS_INVALID) return;
      const SurfacePoint sp = surfaces.at(h, p.dir);
      lsk::Ray r;
      r.origin = lsk::offset_ray_origin(sp.position, sp.geometric_normal, surfaces.scene_scale());
      r.tmin = 0.0f;
      r.dir = lsk::sample_cosine_hemisphere(sp.geometric_normal, lsk::random01(seed, index, 1, 0, 0),
                                            lsk::random01(seed, index, 1, 0, 1));
      r.tmax = lsk::ls_infinity();
      candidates[i] = r;
      ok[i] = 1;
    });
    for (size_t i = 0; i < count && filled < count; ++i)
      if (ok[i]) rays[filled++] = candidates[i];
  }
  return rays;
}

}  // namespace ls
