#include "validate/split_render.h"

#include "common/model/scene.h"
#include "common/structure/accel.h"

#include <utility>

namespace ls {

namespace {

std::vector<glm::vec3> weighted(const std::vector<glm::vec3>& a, int n_a, const std::vector<glm::vec3>& b, int n_b) {
  const double wa = double(n_a) / double(n_a + n_b), wb = double(n_b) / double(n_a + n_b);
  std::vector<glm::vec3> out(a.size());
  for (size_t i = 0; i < a.size(); ++i) out[i] = glm::vec3(wa * glm::dvec3(a[i]) + wb * glm::dvec3(b[i]));
  return out;
}

// Renders samples [first, first + n) into `half` (merged with what it holds).
void add_samples(StudyRenderer& renderer, RenderOptions options, uint32_t first, int n, RenderResult& half, int& spp) {
  if (n <= 0) return;
  options.first_sample = first;
  options.spp = n;
  RenderResult r = renderer.render(options);
  half = spp == 0 ? std::move(r) : combine_renders(half, spp, r, n);
  spp += n;
}

}  // namespace

RenderResult combine_renders(const RenderResult& a, int n_a, const RenderResult& b, int n_b) {
  if (n_b <= 0) return a;
  if (n_a <= 0) return b;
  if (a.width != b.width || a.height != b.height || a.bounce_images.size() != b.bounce_images.size())
    throw InputError("combine_renders: the renders differ in size or bounces");
  RenderResult out;
  out.width = a.width;
  out.height = a.height;
  for (size_t k = 0; k < a.bounce_images.size(); ++k)
    out.bounce_images.push_back(weighted(a.bounce_images[k], n_a, b.bounce_images[k], n_b));
  out.total = weighted(a.total, n_a, b.total, n_b);
  out.bounces = a.bounces;
  for (size_t k = 0; k < out.bounces.size() && k < b.bounces.size(); ++k) {
    BounceStats& s = out.bounces[k];
    const BounceStats& t = b.bounces[k];
    s.extension_rays += t.extension_rays;
    s.shadow_rays += t.shadow_rays;
    s.trace_seconds += t.trace_seconds;
    add_counters(s.ls, t.ls);
    s.switched_extension_rays += t.switched_extension_rays;
    s.switched_shadow_rays += t.switched_shadow_rays;
    s.switched_seconds += t.switched_seconds;
    add_counters(s.switched_ls, t.switched_ls);
  }
  out.dropped_samples = a.dropped_samples + b.dropped_samples;
  out.seconds = a.seconds + b.seconds;
  return out;
}

SplitRender render_split(StudyRenderer& renderer, const RenderOptions& options) {
  if (options.first_sample != 0) throw InputError("render_split: the sample set starts at sample 0");
  SplitRender split;
  extend_split(renderer, options, options.spp, split);
  return split;
}

void extend_split(StudyRenderer& renderer, const RenderOptions& options, int more, SplitRender& split) {
  if (more <= 0) return;
  const uint32_t first = uint32_t(split.total_spp());
  const int n_a = more - more / 2;
  add_samples(renderer, options, first, n_a, split.half[0], split.spp[0]);
  add_samples(renderer, options, first + uint32_t(n_a), more / 2, split.half[1], split.spp[1]);
  split.combined = combine_renders(split.half[0], split.spp[0], split.half[1], split.spp[1]);
}

}  // namespace ls
