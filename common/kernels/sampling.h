// Sampling for the Lambertian path tracer: cosine-weighted directions, uniform points on triangles,
// the power heuristic for multiple importance sampling.  Shared by CPU and GPU so both draw the same
// paths from the same random numbers.  Every sum and product is `precise`: without it a GPU compiler
// may reassociate (lavapipe does) or fuse.  No sin or cos (see cos_sin_turns): bit-identical on
// lavapipe; on real GPUs sqrt and division may differ in the last bits (docs/design.md §11).
#ifndef LS_SAMPLING_H
#define LS_SAMPLING_H

#include "float_bits.h"

#ifdef __cplusplus
namespace lsk {
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

// cos and sin of 2 pi t for t in [0, 1): the quadrant, then Taylor polynomials (to x^15 and x^14,
// error < 1e-11 on [0, pi/2)) in plain arithmetic, so CPU and GPU agree bit for bit where a GPU
// rounds each operation correctly (lavapipe): GLSL's sin and cos, and the C library's, are each their
// own approximation and differ in the last bits.
LS_FN void cos_sin_turns(float t, OUT(float) c, OUT(float) s) {
  precise float t4 = 4.0f * t;
  float q = floor(t4);
  precise float g = (t4 - q) * 1.57079632679490f;
  precise float g2 = g * g;
  precise float sg = g * (1.0f + g2 * (-0.166666666667f + g2 * (8.33333333333e-3f + g2 * (-1.98412698413e-4f +
                     g2 * (2.75573192240e-6f + g2 * (-2.50521083854e-8f + g2 * (1.60590438368e-10f +
                     g2 * -7.64716373182e-13f)))))));
  precise float cg = 1.0f + g2 * (-0.5f + g2 * (4.16666666667e-2f + g2 * (-1.38888888889e-3f + g2 * (2.48015873016e-5f +
                     g2 * (-2.75573192240e-7f + g2 * (2.08767569879e-9f + g2 * -1.14707455977e-11f))))));
  if (q < 1.0f) {
    c = cg;
    s = sg;
  } else if (q < 2.0f) {
    c = -sg;
    s = cg;
  } else if (q < 3.0f) {
    c = -cg;
    s = -sg;
  } else {
    c = sg;
    s = -cg;
  }
}

// A direction about unit n with density cos(theta) / pi.
LS_FN vec3 sample_cosine_hemisphere(IN(vec3) n, float u1, float u2) {
  float r = sqrt(u1);
  float cos_phi;
  float sin_phi;
  cos_sin_turns(u2, cos_phi, sin_phi);
  vec3 b1;
  vec3 b2;
  orthonormal_basis(n, b1, b2);
  precise float one_minus = 1.0f - u1;
  precise vec3 d = b1 * (r * cos_phi) + b2 * (r * sin_phi) + n * sqrt(max(0.0f, one_minus));
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
