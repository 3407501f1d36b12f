#include "validate/policy_study.h"

#include "common/base/median.h"
#include "common/render/render_types.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace ls {
namespace {

const double kNan = std::nan("");

std::string threshold_text(float t) { return shortest_text(t); }

enum class Curve { Rmse, Bias, Threshold };

// The throughput policy's points as (x, y), with the reference as T -> 0.
std::vector<std::pair<double, double>> throughput_curve(const PolicyStudy& study, bool by_speed, Curve y) {
  std::vector<std::pair<double, double>> curve;
  curve.push_back({by_speed ? study.reference_mrays_per_s : 0.0, 0.0});
  for (const PolicyPoint& p : study.points)
    if (p.policy == "throughput")
      curve.push_back({by_speed ? p.mrays_per_s : p.fraction_on_x(),
                       y == Curve::Threshold ? double(p.threshold) : y == Curve::Bias ? p.bias.rmse_bias : p.rmse});
  return curve;
}

}  // namespace

std::string PolicyPoint::label() const {
  return policy == "bounce" ? "from bounce " + std::to_string(start_bounce) : "T = " + threshold_text(threshold);
}

double interpolate(std::vector<std::pair<double, double>> points, double x) {
  std::stable_sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  if (points.empty() || std::isnan(x) || x < points.front().first || x > points.back().first) return kNan;
  for (size_t i = 0; i < points.size(); ++i) {
    if (points[i].first == x) return points[i].second;
    if (i + 1 < points.size() && points[i].first < x && x < points[i + 1].first) {
      const double w = (x - points[i].first) / (points[i + 1].first - points[i].first);
      return points[i].second + w * (points[i + 1].second - points[i].second);
    }
  }
  return kNan;
}

void rays_on_structure(const RenderResult& result, const std::string& structure, const ThroughputSwitch& throughput_switch,
                       uint64_t& on_structure, uint64_t& indirect) {
  on_structure = indirect = 0;
  const bool switch_is_it = throughput_switch.enabled() && throughput_switch.structure.name() == structure;
  for (size_t k = 1; k < result.bounces.size(); ++k) {
    const BounceStats& b = result.bounces[k];
    const uint64_t all = b.extension_rays + b.shadow_rays, switched = b.switched_extension_rays + b.switched_shadow_rays;
    indirect += all;
    if (b.structure == structure) on_structure += all - switched;
    if (switch_is_it) on_structure += switched;
  }
}

std::vector<PolicyComparison> compare_policies(const PolicyStudy& study) {
  std::vector<PolicyComparison> out;
  for (const PolicyPoint& p : study.points) {
    if (p.policy != "bounce") continue;
    PolicyComparison c;
    c.start_bounce = p.start_bounce;
    c.fraction_on_x = p.fraction_on_x();
    c.mrays_per_s = p.mrays_per_s;
    c.bounce_rmse = p.rmse;
    c.throughput_rmse_at_fraction = interpolate(throughput_curve(study, false, Curve::Rmse), c.fraction_on_x);
    c.threshold_at_fraction = interpolate(throughput_curve(study, false, Curve::Threshold), c.fraction_on_x);
    c.throughput_rmse_at_speed = interpolate(throughput_curve(study, true, Curve::Rmse), c.mrays_per_s);
    c.threshold_at_speed = interpolate(throughput_curve(study, true, Curve::Threshold), c.mrays_per_s);
    c.bounce_rmse_bias = p.bias.rmse_bias;
    c.throughput_rmse_bias_at_fraction = interpolate(throughput_curve(study, false, Curve::Bias), c.fraction_on_x);
    c.throughput_rmse_bias_at_speed = interpolate(throughput_curve(study, true, Curve::Bias), c.mrays_per_s);
    out.push_back(c);
  }
  return out;
}

std::vector<float> parse_threshold_list(const std::string& text) {
  std::vector<float> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(parse_switch_threshold(item, "--thresholds " + text));
  if (out.empty() || text.back() == ',') throw InputError("--thresholds '" + text + "': empty item");
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

Table PolicyStudy::points_table() const {
  Table t;
  t.header = {"policy", "start_bounce", "threshold", "fraction_on_x", "mrays_per_s", "speedup_vs_bvh", "rmse",
              "rmse_bias", "rmse_bias_stderr", "noise_floor", "spp", "spp_stop"};
  for (int k = 0; k <= settings.bounces; ++k) t.header.push_back("contribution_rmse_bounce_" + std::to_string(k));
  for (const PolicyPoint& p : points) {
    std::vector<std::string> line = {p.policy, p.policy == "bounce" ? std::to_string(p.start_bounce) : "",
                                     p.policy == "throughput" ? threshold_text(p.threshold) : "", fixed(p.fraction_on_x(), 6),
                                     fixed(p.mrays_per_s, 4),
                                     fixed(reference_mrays_per_s > 0.0 ? p.mrays_per_s / reference_mrays_per_s : 0.0, 4),
                                     fixed(p.rmse, 6), fixed(p.bias.rmse_bias, 6), fixed(p.bias.rmse_bias_stderr, 6),
                                     fixed(p.bias.noise_floor, 6), std::to_string(p.spp), p.spp_stop};
    for (double c : p.contribution_rmse) line.push_back(fixed(c, 6));
    t.rows.push_back(line);
  }
  return t;
}

Table PolicyStudy::comparison_table() const {
  Table t;
  t.header = {"bounce policy", "rays on X", "MRays/s", "RMSE", "rmse_bias",
              "throughput policy, same rays on X: RMSE / rmse_bias (T)",
              "throughput policy, same MRays/s: RMSE / rmse_bias (T)"};
  for (const PolicyComparison& c : comparisons) {
    auto with_t = [](double rmse, double bias, double t) {
      return std::isnan(rmse) ? std::string("- (outside the thresholds)")
                              : rmse_text(rmse) + " / " + rmse_text(bias) + " (" + fixed(t, 3) + ")";
    };
    t.rows.push_back({"from bounce " + std::to_string(c.start_bounce), fixed(100.0 * c.fraction_on_x, 1) + " %",
                      fixed(c.mrays_per_s, 2), rmse_text(c.bounce_rmse), rmse_text(c.bounce_rmse_bias),
                      with_t(c.throughput_rmse_at_fraction, c.throughput_rmse_bias_at_fraction, c.threshold_at_fraction),
                      with_t(c.throughput_rmse_at_speed, c.throughput_rmse_bias_at_speed, c.threshold_at_speed)});
  }
  return t;
}

std::string PolicyStudy::markdown() const {
  Table all;
  all.header = {"policy", "rays on X", "MRays/s", "speed-up vs F-BVH", "spp", "RMSE", "rmse_bias ± stderr", "noise floor"};
  all.rows.push_back({"exact (reference)", "0.0 %", fixed(reference_mrays_per_s, 2), "1.00", "-", rmse_text(0.0),
                      rmse_text(0.0), "-"});
  for (const PolicyPoint& p : points)
    all.rows.push_back({p.policy + ", " + p.label(), fixed(100.0 * p.fraction_on_x(), 1) + " %", fixed(p.mrays_per_s, 2),
                        fixed(reference_mrays_per_s > 0.0 ? p.mrays_per_s / reference_mrays_per_s : 0.0, 2),
                        std::to_string(p.spp) + (p.spp_stop.empty() ? "" : " (" + p.spp_stop + ")"), rmse_text(p.rmse),
                        bias_text(p.bias), rmse_text(p.bias.noise_floor)});
  std::string md = "X = " + structure + "; rays on X = share of the indirect rays (bounces >= 1) traced with X; MRays/s: median of " +
                   std::to_string(repeats) + " round-robin render" + (repeats == 1 ? "" : "s") + "\n\n";
  md += all.markdown() + "\nAt equal speed (the throughput policy interpolated between its neighbouring thresholds; "
        "T -> 0 is the reference):\n\n" + comparison_table().markdown();
  return md;
}

nlohmann::json PolicyStudy::json() const {
  nlohmann::json pts = nlohmann::json::array(), cmp = nlohmann::json::array();
  const auto number = number_or_null;
  for (const PolicyPoint& p : points) {
    nlohmann::json j{{"policy", p.policy},          {"rmse", p.rmse},
                     {"mrays_per_s", p.mrays_per_s}, {"speedup_vs_bvh", reference_mrays_per_s > 0.0 ? p.mrays_per_s / reference_mrays_per_s : 0.0},
                     {"rays_on_x", p.rays_on_x},     {"indirect_rays", p.indirect_rays},
                     {"fraction_on_x", p.fraction_on_x()}, {"contribution_rmse", p.contribution_rmse},
                     {"rmse_bias", number(p.bias.rmse_bias)}, {"rmse_bias_stderr", number(p.bias.rmse_bias_stderr)},
                     {"noise_floor", number(p.bias.noise_floor)}, {"spp", p.spp}};
    if (!p.spp_stop.empty()) j["spp_stop"] = p.spp_stop;
    if (p.policy == "bounce") j["start_bounce"] = p.start_bounce;
    else j["threshold"] = std::stod(threshold_text(p.threshold));  // 0.3, not 0.30000001192092896
    pts.push_back(j);
  }
  for (const PolicyComparison& c : comparisons)
    cmp.push_back({{"start_bounce", c.start_bounce},
                   {"fraction_on_x", c.fraction_on_x},
                   {"mrays_per_s", c.mrays_per_s},
                   {"bounce_rmse", c.bounce_rmse},
                   {"bounce_rmse_bias", number(c.bounce_rmse_bias)},
                   {"throughput_rmse_bias_at_fraction", number(c.throughput_rmse_bias_at_fraction)},
                   {"throughput_rmse_bias_at_speed", number(c.throughput_rmse_bias_at_speed)},
                   {"throughput_rmse_at_fraction", number(c.throughput_rmse_at_fraction)},
                   {"threshold_at_fraction", number(c.threshold_at_fraction)},
                   {"throughput_rmse_at_speed", number(c.throughput_rmse_at_speed)},
                   {"threshold_at_speed", number(c.threshold_at_speed)}});
  nlohmann::json j = study_json(scene, device, settings, reference_mrays_per_s, reference_bytes);
  j["structure"] = structure;
  j["structure_bytes"] = structure_bytes;
  j["repeats"] = repeats;
  j["points"] = pts;
  j["comparisons"] = cmp;
  return j;
}

PolicyStudy run_policy_study(StudyRenderer& renderer, const std::string& scene, const StructureSpec& structure,
                             const std::vector<int>& start_bounces, const std::vector<float>& thresholds,
                             const ImageSettings& settings, const Log& log, int repeats) {
  if (repeats < 1) throw InputError("--repeat must be at least 1");
  for (int k : start_bounces)
    if (k < 1 || k > settings.bounces)
      throw InputError("--start-bounces: " + std::to_string(k) + " is not in [1, --bounces " + std::to_string(settings.bounces) + "]");
  for (float t : thresholds)
    if (!(t > 0.0f) || !std::isfinite(t)) throw InputError("--thresholds: every threshold must be a finite number > 0");
  PolicyStudy study;
  study.scene = scene;
  study.device = renderer.device();
  study.structure = structure.name();
  study.settings = settings;
  study.repeats = repeats;
  study.structure_bytes = renderer.structure(structure).bytes_total();  // refused here if over the budget
  Reference reference = render_reference(renderer, settings);
  reference.timing_rounds = 0;  // timed below: every configuration and the reference, round-robin
  study.reference_mrays_per_s = reference.result.indirect_mrays_per_s();
  study.reference_bytes = reference.bytes;
  log("reference (bvh): " + fixed(study.reference_mrays_per_s, 2) + " MRays/s");

  // Every configuration: its point and its render options.
  std::vector<std::pair<PolicyPoint, RenderOptions>> configs;
  for (int k : start_bounces) {
    PolicyPoint p;
    p.policy = "bounce";
    p.start_bounce = k;
    configs.push_back({p, settings.options(schedule_from(structure, k))});
  }
  for (float t : thresholds) {
    PolicyPoint p;
    p.policy = "throughput";
    p.threshold = t;
    RenderOptions options = settings.options(parse_schedule("bvh"));
    options.throughput_switch = ThroughputSwitch{t, structure};
    configs.push_back({p, options});
  }
  // The first round measures everything; later ones only time (same images: same RMSE), round-robin.
  std::vector<std::vector<double>> speeds(configs.size() + 1);
  speeds.back().push_back(study.reference_mrays_per_s);
  for (size_t i = 0; i < configs.size(); ++i) {
    auto& [p, options] = configs[i];
    const Measured m = measure(renderer, options, reference, settings.auto_spp);
    p.rmse = m.rmse;
    p.contribution_rmse = m.contribution_rmse;
    p.bias = m.bias;
    p.spp = m.spp;
    p.spp_stop = m.spp_stop;
    speeds[i].push_back(m.mrays_per_s);
    rays_on_structure(m.result, study.structure, options.throughput_switch, p.rays_on_x, p.indirect_rays);
    log("[" + std::to_string(i + 1) + "/" + std::to_string(configs.size()) + "] " + p.policy + ", " + p.label() + ": " +
        fixed(100.0 * p.fraction_on_x(), 1) + " % of the rays on " + study.structure + ", RMSE " + rmse_text(p.rmse) +
        ", rmse_bias " + bias_text(p.bias) + " (" + spp_text(m) + ")" +
        ", " + fixed(m.mrays_per_s, 2) + " MRays/s");
  }
  for (int r = 1; r < repeats; ++r) {
    speeds.back().push_back(renderer.render(settings.options(parse_schedule("bvh"))).indirect_mrays_per_s());
    for (size_t i = 0; i < configs.size(); ++i) speeds[i].push_back(renderer.render(configs[i].second).indirect_mrays_per_s());
    log("timing round " + std::to_string(r + 1) + "/" + std::to_string(repeats) + " done");
  }
  study.reference_mrays_per_s = median(speeds.back());
  for (size_t i = 0; i < configs.size(); ++i) {
    configs[i].first.mrays_per_s = median(speeds[i]);
    study.points.push_back(configs[i].first);
  }
  study.comparisons = compare_policies(study);
  return study;
}

void write_policy_study(const std::string& dir, const PolicyStudy& study) {
  std::filesystem::create_directories(dir);
  write_text_file(dir + "/policy.md", study.markdown());
  write_text_file(dir + "/policy.csv", study.points_table().csv());
  write_text_file(dir + "/policy.json", study.json().dump(2) + "\n");
}

}  // namespace ls
