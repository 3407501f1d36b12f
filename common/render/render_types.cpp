#include "common/render/render_types.h"

#include <algorithm>
#include <limits>

namespace ls {

void average_passes(RenderResult& result, int spp) {
  const size_t pixels = size_t(result.width) * result.height;
  const float inv_spp = 1.0f / float(std::max(1, spp));
  result.total.assign(pixels, glm::vec3(0.0f));
  for (auto& img : result.bounce_images)
    for (size_t p = 0; p < pixels; ++p) img[p] *= inv_spp;
  // The total adds finite bounce images; one whose sum passes the float range keeps the largest
  // float instead (and is counted with the dropped samples): no image ever holds Inf or NaN.
  for (size_t p = 0; p < pixels; ++p) {
    glm::dvec3 sum(0.0);
    for (const auto& img : result.bounce_images) sum += glm::dvec3(img[p]);
    const glm::dvec3 clamped = glm::min(sum, glm::dvec3(double(std::numeric_limits<float>::max())));
    result.total[p] = glm::vec3(clamped);
    if (clamped != sum) ++result.dropped_samples;
  }
}

std::vector<uint32_t> render_pixels(const RenderOptions& options) {
  const uint32_t pixels = options.width * options.height;
  if (options.pixels.empty()) {
    std::vector<uint32_t> all(pixels);
    for (uint32_t p = 0; p < pixels; ++p) all[p] = p;
    return all;
  }
  for (size_t i = 0; i < options.pixels.size(); ++i)
    if (options.pixels[i] >= pixels || (i > 0 && options.pixels[i] <= options.pixels[i - 1]))
      throw InputError("render: the pixels to render must be ascending indices into the image");
  return options.pixels;
}

uint64_t RenderResult::indirect_rays() const {
  uint64_t n = 0;
  for (size_t k = 1; k < bounces.size(); ++k) n += bounces[k].extension_rays + bounces[k].shadow_rays;
  return n;
}

double RenderResult::indirect_seconds() const {
  double s = 0.0;
  for (size_t k = 1; k < bounces.size(); ++k) s += bounces[k].trace_seconds;
  return s;
}

double RenderResult::indirect_mrays_per_s() const {
  const double s = indirect_seconds();
  return s > 0.0 ? double(indirect_rays()) / s * 1e-6 : 0.0;
}

std::vector<StructureSpec> render_structures(const RenderOptions& options) {
  std::vector<StructureSpec> specs;
  auto add = [&](const StructureSpec& spec) {
    for (const StructureSpec& s : specs)
      if (s == spec) return;
    specs.push_back(spec);
  };
  for (int k = 0; k <= options.bounces; ++k) add(options.schedule.at(k));
  if (options.throughput_switch.enabled()) add(options.throughput_switch.structure);
  return specs;
}

}  // namespace ls
