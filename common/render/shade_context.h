// The C++ stand-in for the shading shader's bound buffers (gpu/shaders/shade.comp): the single-source
// path-tracing kernel common/kernels/shade_path.h is included inside this struct, so `lights[i]` in the
// kernel reads the pointer member here and the buffer there.
#pragma once

#include "common/kernels/camera.h"
#include "common/kernels/float_bits.h"
#include "common/kernels/layouts.h"
#include "common/kernels/offset_ray.h"
#include "common/kernels/rng.h"
#include "common/kernels/sampling.h"
#include "common/kernels/scaled_geometry.h"

namespace lsk {

struct ShadeContext {
  const ShadeInstance* shade_instances = nullptr;
  const ShadeVertex* shade_vertices = nullptr;
  const ShadeTriangle* shade_triangles = nullptr;
  const ShadeMaterial* materials = nullptr;
  const ShadeLight* lights = nullptr;
  const float* light_cdf = nullptr;
  ShadeParams shade{};

#include "common/kernels/shade_path.h"
};

}  // namespace lsk
