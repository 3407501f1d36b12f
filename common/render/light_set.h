// The scene's lights and the shading kernel's context for a render, shared by both path tracers.
#pragma once

#include "common/model/scene.h"
#include "common/render/render_types.h"
#include "common/render/shade_context.h"
#include "common/render/surface.h"

#include <vector>

namespace ls {

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

}  // namespace ls
