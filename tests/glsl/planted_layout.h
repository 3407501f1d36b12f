// A struct laid out differently by C++ (vec3 4-aligned: b at 4) and std430 (vec3 16-aligned: b at
// 16): tests/glsl/layouts_offsets.cmake must turn it into a static_assert that fails.
#ifndef LS_PLANTED_LAYOUT_H
#define LS_PLANTED_LAYOUT_H
#include "../../common/kernels/glsl_compat.h"
#ifdef __cplusplus
namespace lsk {
#endif
struct Planted {
  float a;
  vec3 b;
};
#ifdef __cplusplus
}  // namespace lsk
#endif
#endif
