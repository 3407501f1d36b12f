// The SPIR-V of gpu/shaders/*.comp, compiled by glslangValidator at build time and embedded.
#pragma once

#include <cstdint>
#include <vector>

namespace ls::gpu {
const std::vector<uint32_t>& spirv_trace();          // shaders/trace.comp
const std::vector<uint32_t>& spirv_ls_candidates();  // shaders/ls_candidates.comp
const std::vector<uint32_t>& spirv_shade();          // shaders/shade.comp
}  // namespace ls::gpu
