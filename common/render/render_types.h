// What a render is asked and what it gives, whichever back end renders it (the CPU path tracer,
// cpu/render/path_tracer.h, or the GPU's, gpu/gpu_renderer.h): options, per-bounce statistics, images.
#pragma once

#include "common/model/structure_name.h"
#include "common/render/throughput_switch.h"
#include "common/structure/accel.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ls {

struct RenderOptions {
  Schedule schedule;
  LsLookup lookup;  // every Line Space lookup of the render (the angle, the behind mode)
  int spp = 16;
  int bounces = 3;  // indirect segments after the primary hit
  uint32_t width = 512;
  uint32_t height = 512;
  uint32_t seed = 1;
  // The sample indices are first_sample .. first_sample + spp - 1 (the random numbers' sample key): the
  // validator renders one sample set as two disjoint halves (validate/split_render.h).  0: as ever.
  uint32_t first_sample = 0;
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

// Turns the bounce images' sums over spp passes into averages and fills the total image (clamped to
// the float range; each clamped pixel counts as a dropped sample).
void average_passes(RenderResult& result, int spp);

// The structures a render needs: each distinct schedule entry up to `bounces`, and the switch's.
std::vector<StructureSpec> render_structures(const RenderOptions& options);

}  // namespace ls
