// The host side of the push-constant block `Params` in shaders/scene_buffers.glsl (same order).
#pragma once

#include <cstdint>

namespace ls::gpu {

struct ShaderParams {
  uint32_t ls_enabled = 0;
  uint32_t ls_n = 0;
  float ls_cos2 = -1.0f;
  uint32_t two_level = 0;
  uint32_t any_hit = 0;
  uint32_t first = 0;
  uint32_t count = 0;
  uint32_t ls_reverse = 0;
  uint32_t further_rays = 0;
  uint32_t search_instance = 0;
  uint32_t first_ls = 0;
  uint32_t ls_count = 0;
};
static_assert(sizeof(ShaderParams) == 48, "must match the GLSL push-constant block");

}  // namespace ls::gpu
