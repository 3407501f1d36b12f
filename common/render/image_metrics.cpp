#include "common/render/image_metrics.h"

#include "common/kernels/sampling.h"
#include "common/model/scene.h"

#include <algorithm>
#include <cmath>

namespace ls {

float exposure_scale(const std::vector<glm::vec3>& reference) {
  if (reference.empty()) return 1.0f;
  std::vector<float> lum(reference.size());
  for (size_t i = 0; i < reference.size(); ++i) lum[i] = lsk::luminance(reference[i]);
  const size_t k = std::min(lum.size() - 1, size_t(std::floor(0.99 * double(lum.size() - 1))));
  std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(k), lum.end());
  const float p99 = lum[k];
  return p99 > 0.0f && std::isfinite(p99) ? 1.0f / p99 : 1.0f;
}

double rmse(const std::vector<glm::vec3>& reference, const std::vector<glm::vec3>& image, float scale) {
  if (reference.size() != image.size())
    throw InputError("rmse: images differ in size (" + std::to_string(reference.size()) + " and " +
                     std::to_string(image.size()) + " pixels)");
  if (reference.empty()) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < reference.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double a = std::clamp(double(reference[i][c]) * scale, 0.0, 1.0);
      const double b = std::clamp(double(image[i][c]) * scale, 0.0, 1.0);
      sum += (a - b) * (a - b);
    }
  return std::sqrt(sum / (3.0 * double(reference.size())));
}

}  // namespace ls
