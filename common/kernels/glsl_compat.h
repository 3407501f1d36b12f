// The prelude that lets one source be both GLSL 4.50 and C++20 (docs/design.md §4, §11).
//
// Rules for every file in common/kernels/:
//  - float literals carry the `f` suffix; unsigned literals the `u` suffix;
//  - no constructors, brace initialisation, references, pointers, recursion or templates;
//  - parameters are written IN(T) x, OUT(T) x, INOUT(T) x; never pass one variable as both an
//    IN and an OUT argument (GLSL copies, C++ aliases);
//  - arithmetic whose rounding decides a result is marked `precise` (GLSL NoContraction; on the C++
//    side -ffp-contract=off does the same job for the whole program);
//  - every function starts with LS_FN (C++ `inline`, so headers can be included by many files);
//  - `#ifndef` guards, not `#pragma once`.
// Functions that read the scene's buffers live in files meant to be included inside a C++ struct that
// holds the buffers as pointers (common/structure/trace_context.h, common/render/shade_context.h), so `nodes[i]` reads the same in both.
#ifndef LS_GLSL_COMPAT_H
#define LS_GLSL_COMPAT_H

#ifdef __cplusplus
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/packing.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace lsk {
using uint = std::uint32_t;
using glm::ivec3;
using glm::mat3;
using glm::mat4;
using glm::uvec2;
using glm::uvec3;
using glm::uvec4;
using glm::vec2;
using glm::vec3;
using glm::vec4;

using glm::clamp;
using glm::cross;
using glm::dot;
using glm::floatBitsToInt;
using glm::floor;
using glm::floatBitsToUint;
using glm::intBitsToFloat;
using glm::isinf;
using glm::isnan;
using glm::ldexp;
using glm::uintBitsToFloat;
using glm::length;
using glm::max;
using glm::min;
using glm::normalize;
using glm::sqrt;
using glm::unpackSnorm2x16;
inline float inversesqrt(float x) { return 1.0f / std::sqrt(x); }
// |x| with the sign bit cleared (IEEE 754's abs, and what GPUs compile GLSL's abs to), one
// instruction.  glm's (x >= 0 ? x : -x, which keeps -0 and flips a NaN's sign) became a jump in some
// callers, which rays of random direction signs mispredicted half the time (f-ls:8:6's ray set-up
// on fireplace: 2.8 a ray).  No kernel's result depends on the sign of a zero or a NaN that abs
// returns: each use compares it (alone, or as t's slack), takes its exponent, or subtracts it from 1.
inline float abs(float x) { return std::fabs(x); }
inline vec3 abs(const vec3& v) { return vec3(std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)); }
}  // namespace lsk

#define IN(T) const T&
#define OUT(T) T&
#define INOUT(T) T&
#define precise
#define LS_CONST static constexpr
#define LS_FN inline
#define LS_CACHE_LINE alignas(64)  // host arrays of the struct start each element on a cache line
#else
#define IN(T) in T
#define OUT(T) out T
#define INOUT(T) inout T
#define LS_CONST const
#define LS_FN
#define LS_CACHE_LINE
#endif

#endif
