// Sampling for the Lambertian path tracer: cosine-weighted directions, uniform points on triangles,
// the power heuristic for multiple importance sampling.  Shared by CPU and GPU so both draw the same
// paths from the same random numbers.  Every sum and product is `precise`: without it a GPU compiler
// may reassociate (lavapipe does) or fuse.  Bit-identical on lavapipe except sin and cos, which differ
// from the C library's in the last bits; sqrt and division differ on real GPUs (TOOLCHAIN.md).
#ifndef LS_SAMPLING_H
#define LS_SAMPLING_H

#include "float_bits.h"

#ifdef __cplusplus
#include <cmath>
namespace lsk {
using std::cos;
using std::sin;
#endif

LS_CONST float LS_PI = 3.14159265358979f;

// An orthonormal basis around unit n (Duff et al., "Building an Orthonormal Basis, Revisited", 2017).
LS_FN void orthonormal_basis(IN(vec3) n, OUT(vec3) b1, OUT(vec3) b2) {
  float s = n.z >= 0.0f ? 1.0f : -1.0f;
  precise float a = -1.0f / (s + n.z);
  precise float b = n.x * n.y * a;
  precise float b1x = 1.0f + s * n.x * n.x * a;
  precise float b1y = s * b;
  precise float b2y = s + n.y * n.y * a;
  b1 = vec3(b1x, b1y, -s * n.x);
  b2 = vec3(b, b2y, -n.y);
}

// A direction about unit n with density cos(theta) / pi.
LS_FN vec3 sample_cosine_hemisphere(IN(vec3) n, float u1, float u2) {
  float r = sqrt(u1);
  precise float phi = 2.0f * LS_PI * u2;
  vec3 b1;
  vec3 b2;
  orthonormal_basis(n, b1, b2);
  precise float one_minus = 1.0f - u1;
  precise vec3 d = b1 * (r * cos(phi)) + b2 * (r * sin(phi)) + n * sqrt(max(0.0f, one_minus));
  return normalize_in_order(d);
}

// A uniformly distributed point on a triangle.
LS_FN vec3 sample_triangle(IN(vec3) p0, IN(vec3) p1, IN(vec3) p2, float u1, float u2) {
  float su = sqrt(u1);
  precise float b0 = 1.0f - su;
  precise float b1 = u2 * su;
  precise float b2 = 1.0f - b0 - b1;
  precise vec3 q = p0 * b0 + p1 * b1 + p2 * b2;
  return q;
}

LS_FN float power_heuristic(float pdf_a, float pdf_b) {
  precise float a2 = pdf_a * pdf_a;
  precise float b2 = pdf_b * pdf_b;
  precise float sum = a2 + b2;
  precise float w = a2 / sum;
  return sum > 0.0f ? w : 0.0f;
}

LS_FN float luminance(IN(vec3) c) {
  precise float y = 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
  return y;
}

#ifdef __cplusplus
}  // namespace lsk
#endif

#endif
