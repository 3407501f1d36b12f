#include "validate/bias_estimate.h"

#include "common/model/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace ls {

BiasEstimate estimate_bias(const std::vector<glm::vec3>& ref_a, const std::vector<glm::vec3>& image_a,
                           const std::vector<glm::vec3>& ref_b, const std::vector<glm::vec3>& image_b, float scale,
                           int n_a, int n_b) {
  const size_t n = ref_a.size();
  BiasEstimate e;
  e.pixels = n;
  if (n_a <= 0 || n_b <= 0 || n == 0) {  // a half without samples has no images
    e.rmse_bias = e.rmse_bias_stderr = e.mean_product = e.mean_product_stderr = e.noise_floor = NAN;
    return e;
  }
  if (image_a.size() != n || ref_b.size() != n || image_b.size() != n)
    throw InputError("rmse_bias: the four images differ in size");
  const auto scaled = [scale](float v) { return std::clamp(double(v) * scale, 0.0, 1.0); };
  // Welford's running mean and variance of the per-pixel products (no cancellation at small bias).
  double mean = 0.0, m2 = 0.0, spread = 0.0;
  size_t nonzero = 0;
  for (size_t i = 0; i < n; ++i) {
    double product = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double da = scaled(image_a[i][c]) - scaled(ref_a[i][c]);
      const double db = scaled(image_b[i][c]) - scaled(ref_b[i][c]);
      product += da * db;
      spread += (da - db) * (da - db);
    }
    product /= 3.0;
    nonzero += product != 0.0;
    const double delta = product - mean;
    mean += delta / double(i + 1);
    m2 += delta * (product - mean);
  }
  const double total = double(n_a) + double(n_b);
  e.noise_floor = std::sqrt(spread / (3.0 * double(n)) * double(n_a) * double(n_b) / (total * total));
  if (nonzero == 0 && spread > 0.0) {  // differences, none in both halves: undetermined
    e.mean_product = 0.0;
    e.rmse_bias = e.rmse_bias_stderr = e.mean_product_stderr = NAN;
    return e;
  }
  e.mean_product = mean;
  e.mean_product_stderr = n > 1 ? std::sqrt(m2 / double(n - 1) / double(n)) : NAN;
  const double m = std::max(mean, 0.0);
  e.rmse_bias = std::sqrt(m);
  e.rmse_bias_stderr = std::sqrt(m + e.mean_product_stderr) - e.rmse_bias;
  return e;
}

}  // namespace ls
