#include "validate/heatmap.h"

#include "common/model/scene.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace ls {

namespace {

// sRGB display colour to the linear value write_png turns back into it.
float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

glm::vec3 ramp(float x) {
  static const std::array<glm::vec3, 8> stops = {glm::vec3(0, 0, 4),      glm::vec3(40, 11, 84),
                                                 glm::vec3(101, 21, 110), glm::vec3(159, 42, 99),
                                                 glm::vec3(212, 72, 66),  glm::vec3(245, 125, 21),
                                                 glm::vec3(250, 193, 39), glm::vec3(252, 255, 164)};
  const float t = std::clamp(x, 0.0f, 1.0f) * float(stops.size() - 1);
  const size_t i = std::min(size_t(t), stops.size() - 2);
  const glm::vec3 c = glm::mix(stops[i], stops[i + 1], t - float(i)) / 255.0f;
  return {srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)};
}

void check_sizes(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.pixels.size() != b.pixels.size())
    throw InputError("heat-map: images differ in size");
}

}  // namespace

std::vector<float> pixel_errors(const Image& reference, const Image& image, float scale) {
  check_sizes(reference, image);
  std::vector<float> e(reference.pixels.size());
  for (size_t i = 0; i < e.size(); ++i) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double a = std::clamp(double(reference.pixels[i][c]) * scale, 0.0, 1.0);
      const double b = std::clamp(double(image.pixels[i][c]) * scale, 0.0, 1.0);
      sum += (a - b) * (a - b);
    }
    e[i] = float(std::sqrt(sum / 3.0));
  }
  return e;
}

Image error_heatmap(const Image& reference, const Image& image, float scale, float max_error) {
  const std::vector<float> e = pixel_errors(reference, image, scale);
  Image out{reference.width, reference.height, std::vector<glm::vec3>(e.size())};
  for (size_t i = 0; i < e.size(); ++i) out.pixels[i] = ramp(e[i] / max_error);
  return out;
}

void write_error_images(const std::string& prefix, const Image& reference, const Image& image, float scale,
                        float max_error) {
  const Image heat = error_heatmap(reference, image, scale, max_error);
  write_png(prefix + "_heatmap.png", heat);
  const uint32_t w = reference.width, h = reference.height, gap = 4, total_w = 3 * w + 2 * gap;
  Image side{total_w, h, std::vector<glm::vec3>(size_t(total_w) * h, glm::vec3(1.0f))};
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t src = size_t(y) * w + x, row = size_t(y) * total_w;
      side.pixels[row + x] = reference.pixels[src] * scale;
      side.pixels[row + w + gap + x] = image.pixels[src] * scale;
      side.pixels[row + 2 * (w + gap) + x] = heat.pixels[src];
    }
  write_png(prefix + "_side_by_side.png", side);
}

}  // namespace ls
