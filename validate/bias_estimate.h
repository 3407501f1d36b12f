// The error of an approximation apart from sampling noise (docs/design.md §7): rmse_bias, the RMSE
// between the *expected* approximate and reference images, estimated from two renders of each over
// disjoint sample halves A and B (validate/split_render.h).  Per pixel and channel, with d = approximation
// - reference on the images scaled by e and clamped to [0, 1] as rmse() does, d_A and d_B are
// independent with the same mean (the bias), so E[d_A * d_B] = bias^2 exactly, noise or not.
#pragma once

#include <glm/glm.hpp>

#include <cstddef>
#include <vector>

namespace ls {

struct BiasEstimate {
  // sqrt(max(0, mean product)); NaN when there is no second half (1 sample per pixel), and when the
  // halves differ from the reference but never in the same pixel: every product is 0, so its spread
  // says nothing and "0 +- 0" would claim a certainty the samples do not have (a small image at few
  // spp, where an approximation's errors are sparse).
  double rmse_bias = 0.0;
  // One standard error of rmse_bias: sqrt(max(0, m) + se(m)) - sqrt(max(0, m)) with m the mean product,
  // se(m) = sd / sqrt(pixels) of the per-pixel products (RGB averaged: the pixels are independent, their
  // channels are not).  For m >> se(m) this is the delta method's se(m) / (2 rmse_bias); at m <= 0 it is
  // sqrt(se(m)), the bias one standard error of m could hide, instead of the delta method's infinity.
  double rmse_bias_stderr = 0.0;
  double mean_product = 0.0, mean_product_stderr = 0.0;
  // RMS of the sampling noise left in the difference of the images averaged over both halves (what the
  // heat-maps show): sqrt(mean (d_A - d_B)^2 * n_A n_B / (n_A + n_B)^2).  rmse^2 ~ rmse_bias^2 + this^2.
  double noise_floor = 0.0;
  size_t pixels = 0;
  bool valid() const { return rmse_bias == rmse_bias; }
};

// ref_a, image_a: the halves of n_a samples; ref_b, image_b: of n_b.  Throws InputError when sizes differ.
// n_b == 0: no estimate (NaN figures).
BiasEstimate estimate_bias(const std::vector<glm::vec3>& ref_a, const std::vector<glm::vec3>& image_a,
                           const std::vector<glm::vec3>& ref_b, const std::vector<glm::vec3>& image_b, float scale,
                           int n_a, int n_b);

}  // namespace ls
