#include "validate/measure.h"

#include "common/base/median.h"
#include "common/render/image_metrics.h"
#include "common/render/render_types.h"
#include "validate/table.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace ls {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

nlohmann::json SppAuto::json() const {
  if (!enabled) return nullptr;
  return {{"rel_stderr", rel_stderr}, {"seconds", seconds}, {"max_spp", max_spp}};
}

RenderOptions ImageSettings::options(const Schedule& schedule) const {
  RenderOptions o;
  o.schedule = schedule;
  o.width = width;
  o.height = height;
  o.spp = spp;
  o.bounces = bounces;
  o.seed = seed;
  o.lookup = lookup;
  return o;
}

const SplitRender& Reference::at(StudyRenderer& renderer, int total) {
  for (const SplitRender& level : levels)
    if (level.total_spp() == total) return level;
  while (levels.back().total_spp() < total) {
    SplitRender next = levels.back();
    extend_split(renderer, options, next.total_spp(), next);
    levels.push_back(std::move(next));
  }
  if (levels.back().total_spp() != total)
    throw InputError("reference: " + std::to_string(total) + " spp is not a doubling of " +
                     std::to_string(levels.front().total_spp()));
  return levels.back();
}

Reference render_reference(StudyRenderer& renderer, const ImageSettings& settings) {
  const Schedule exact = parse_schedule("bvh");
  Reference r;
  r.options = settings.options(exact);
  r.timing_rounds = settings.timing_rounds;
  r.levels.push_back(render_split(renderer, r.options));
  r.result = r.levels.front().combined;
  r.scale = exposure_scale(r.result.total);
  r.bytes = schedule_bytes(renderer, exact, settings.bounces);
  return r;
}

namespace {

// m's speed: round 1 times m's own render (both halves) and then the exact F-BVH's; each further
// round renders both again, one right after the other, at m's spp.
void time_beside_exact(StudyRenderer& renderer, const RenderOptions& options, Reference& reference, Measured& m) {
  if (reference.timing_rounds == 0) {  // the study times its configurations itself
    m.mrays_per_s = m.result.indirect_mrays_per_s();
    return;
  }
  RenderOptions config = options;
  config.spp = m.spp;
  RenderOptions exact = reference.options;
  exact.spp = m.spp;
  std::vector<double> own{m.result.indirect_mrays_per_s()}, exact_speed, ratio;
  for (int round = 0; round < reference.timing_rounds; ++round) {
    if (round > 0) own.push_back(renderer.render(config).indirect_mrays_per_s());
    exact_speed.push_back(renderer.render(exact).indirect_mrays_per_s());
    ratio.push_back(exact_speed.back() > 0.0 ? own.back() / exact_speed.back() : 0.0);
  }
  m.mrays_per_s = median(own);
  m.exact_mrays_per_s = median(exact_speed);
  m.speedup = median(ratio);
}

}  // namespace

Measured measure(StudyRenderer& renderer, const Schedule& schedule, const ImageSettings& settings, Reference& reference) {
  return measure(renderer, settings.options(schedule), reference, settings.auto_spp);
}

Measured measure(StudyRenderer& renderer, const RenderOptions& options, Reference& reference, const SppAuto& auto_spp) {
  Measured m;
  m.schedule = options.schedule.name();
  const auto t0 = std::chrono::steady_clock::now();
  SplitRender split = render_split(renderer, options);
  const SplitRender* ref = nullptr;
  for (;;) {
    ref = &reference.at(renderer, split.total_spp());
    m.bias = estimate_bias(ref->half[0].total, split.half[0].total, ref->half[1].total, split.half[1].total,
                           reference.scale, split.spp[0], split.spp[1]);
    if (!auto_spp.enabled) break;
    if (m.bias.valid() && m.bias.rmse_bias_stderr <= auto_spp.rel_stderr * m.bias.rmse_bias) {
      m.spp_stop = "converged";
      break;
    }
    if (2 * split.total_spp() > auto_spp.max_spp) {
      m.spp_stop = "max spp";
      break;
    }
    if (2.0 * seconds_since(t0) > auto_spp.seconds) {  // doubling costs about what all so far did
      m.spp_stop = "time budget";
      break;
    }
    extend_split(renderer, options, split.total_spp(), split);
  }
  m.spp = split.total_spp();
  m.result = std::move(split.combined);
  m.reference_total = ref->combined.total;
  m.rmse = rmse(ref->combined.total, m.result.total, reference.scale);
  for (size_t k = 0; k < m.result.bounce_images.size(); ++k)
    m.contribution_rmse.push_back(rmse(ref->combined.bounce_images[k], m.result.bounce_images[k], reference.scale));
  time_beside_exact(renderer, options, reference, m);
  for (const StructureSpec& spec : render_structures(options)) m.bytes += renderer.structure(spec).bytes_total();
  return m;
}

std::string spp_text(const Measured& m) {
  return std::to_string(m.spp) + " spp" + (m.spp_stop.empty() ? "" : ", " + m.spp_stop);
}

std::string bias_text(const BiasEstimate& b) {
  if (!b.valid()) return "-";
  // Two significant digits of the standard error, at least the paper's four decimals.
  const int decimals = b.rmse_bias_stderr > 0.0 ? std::clamp(1 - int(std::floor(std::log10(b.rmse_bias_stderr))), 4, 7) : 4;
  const auto text = [decimals](double v) {
    const std::string s = fixed(v, decimals);
    return s.rfind("0.", 0) == 0 ? s.substr(1) : s;
  };
  return text(b.rmse_bias) + " ± " + text(b.rmse_bias_stderr);
}

nlohmann::json number_or_null(double v) { return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v); }

nlohmann::json study_json(const std::string& scene, const std::string& device, const ImageSettings& settings,
                          double reference_mrays_per_s, size_t reference_bytes) {
  return {{"scene", scene},
          {"device", device},
          {"width", settings.width},
          {"height", settings.height},
          {"spp", settings.spp},
          {"spp_auto", settings.auto_spp.json()},
          {"bounces", settings.bounces},
          {"seed", settings.seed},
          // null where no reference was rendered (paper --tables 2 builds only)
          {"reference", reference_mrays_per_s > 0.0 ? nlohmann::json{{"structure", "bvh"}, {"mrays_per_s", reference_mrays_per_s},
                                                                     {"bytes", reference_bytes}}
                                                   : nlohmann::json(nullptr)}};
}

}  // namespace ls
