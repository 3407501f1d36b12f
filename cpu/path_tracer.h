// The CPU path tracer: Lambertian surfaces, emissive triangles as area lights with next-event
// estimation and multiple importance sampling (power heuristic), a background radiance for rays that
// leave the scene, and the acceleration structure chosen per bounce by a schedule.
//
// Bounces (DESIGN §3): bounce 0 is the camera ray and the shadow ray from its hit; bounce k >= 1 is
// the k-th indirect segment and the shadow ray from its hit.  The image of bounce k holds what the
// rays of bounce k found: emission hit by its segment (MIS-weighted; weight 1 at bounce 0) plus the
// light its shadow ray let through.  The total image is their sum.  At the last bounce the light
// sample takes the full weight, since no further segment could find that light by BSDF sampling:
// the render is then an unbiased estimate of light paths with at most bounces + 2 segments.
//
// It runs as a wavefront, one sample per pixel per pass: all rays of one bounce are traced as one
// batch on all threads, so the time spent tracing each bounce is measured apart from shading.
// Random numbers are keyed by (seed, pixel, sample, bounce, dimension): a render whose schedule is
// exact before bounce k follows exactly the same paths as the all-exact render up to bounce k.
#pragma once

#include "accel.h"
#include "scene.h"
#include "shade_context.h"
#include "structure_name.h"
#include "surface.h"
#include "throughput_switch.h"

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace ls {

struct RenderOptions {
  Schedule schedule;
  int spp = 16;
  int bounces = 3;  // indirect segments after the primary hit
  uint32_t width = 512;
  uint32_t height = 512;
  uint32_t seed = 1;
  // The pixels to render, row-major indices in ascending order (a sharded render's tiles:
  // tile_selection.h); empty: every pixel.  The others stay black and trace no ray.  Random numbers are
  // keyed by the global pixel index, so a rendered pixel's value does not depend on which others are.
  std::vector<uint32_t> pixels;
  // Paths whose throughput is below a threshold trace a bounce's rays with another structure
  // (throughput_switch.h); off by default.
  ThroughputSwitch throughput_switch;
};

// options.pixels, or every pixel when it is empty; throws InputError unless ascending and in the image.
std::vector<uint32_t> render_pixels(const RenderOptions& options);

struct BounceStats {
  uint64_t extension_rays = 0;  // camera rays at bounce 0
  uint64_t shadow_rays = 0;
  double trace_seconds = 0.0;   // wall-clock time spent inside trace batches
  std::string structure;
  lsk::LsCounters ls{};         // Line Space lookups of this bounce's rays
  // The part of the above traced with the throughput switch's structure (all zero when it is off).
  uint64_t switched_extension_rays = 0;
  uint64_t switched_shadow_rays = 0;
  double switched_seconds = 0.0;
  lsk::LsCounters switched_ls{};
};

struct RenderResult {
  uint32_t width = 0, height = 0;
  std::vector<std::vector<glm::vec3>> bounce_images;  // bounces + 1 images, row-major, top row first
  std::vector<glm::vec3> total;
  std::vector<BounceStats> bounces;
  uint64_t dropped_samples = 0;  // contributions left out as non-finite (or whose sum would be), and
                                 // total pixels clamped to the float range: images hold no Inf/NaN
  double seconds = 0.0;                               // whole render, shading included
  uint64_t indirect_rays() const;
  double indirect_seconds() const;
  double indirect_mrays_per_s() const;
};

// progress(done, total) is called after every pass (one sample per pixel).
using Progress = std::function<void(int done, int total)>;

// Traces one batch of rays with a structure, like trace_rays() (any_hit: the shadow rays, of which
// only whether they are blocked is read); the GPU port passes its own.
using BatchTracer = std::function<void(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                                       lsk::LsCounters* counters)>;

// Emissive world triangles with a CDF by power (area x luminance of emission), as the shading
// kernel's arrays (common/kernels/shade_path.h).  Areas, distances and densities are in scene units
// (kernels/scaled_geometry.h), so they stay finite at 1e20 and 1e-20.
struct LightSet {
  std::vector<lsk::ShadeLight> lights;
  std::vector<float> cdf;  // inclusive, last == 1
  float total_power = 0.0f;
  int unit_k = 0;  // areas, distances and densities are in scene units (lengths x 2^unit_k)
  LightSet(const Scene& scene, const SurfaceLookup& surfaces);
};

// The shading kernel's context for a render: the surfaces' arrays, the lights and the options.
lsk::ShadeContext shade_context(const SurfaceLookup& surfaces, const LightSet& lights, const RenderOptions& options);

// Turns the bounce images' sums over spp passes into averages and fills the total image (clamped to
// the float range; each clamped pixel counts as a dropped sample).
void average_passes(RenderResult& result, int spp);

// structures: built structures keyed by canonical name; every schedule entry (and the throughput
// switch's structure, when it is on) must be present.
// tracer: where the batches are traced (empty: trace_rays, and trace_occlusion for shadow rays, on
// all CPU threads).
RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures, const RenderOptions& options,
                    const Progress& progress = {}, const BatchTracer& tracer = {});

// Builds each distinct structure of the schedule once (and the throughput switch's, when given and on).
std::map<std::string, Accel> build_schedule_structures(const Scene& scene, const Schedule& schedule,
                                                       const AccelOptions& options = {},
                                                       const ThroughputSwitch& throughput_switch = {});

// The structures a render needs: each distinct schedule entry up to `bounces`, and the switch's.
std::vector<StructureSpec> render_structures(const RenderOptions& options);

}  // namespace ls
