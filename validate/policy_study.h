// `linespace-validate policy`: two ways of choosing which rays the approximate structure X traces,
// compared at equal speed on one scene (the paper's section 4 suggests both):
//   bounce policy      exact F-BVH before bounce k, X from bounce k on (the paper's rule);
//   throughput policy  exact F-BVH, except that a path whose throughput luminance is below T traces
//                      that bounce's rays with X (render --throughput-switch T:X).
// Every render uses the all-exact reference's random numbers; RMSE and rmse_bias as in `rmse`
// (docs/design.md §7, measure.h).  Per configuration: RMSE, indirect MRays/s and the fraction of indirect
// rays (bounces >= 1) traced with X.  Then, for each bounce-policy point, the throughput policy's RMSE
// interpolated linearly between its two neighbouring points at the same fraction of rays on X, and at
// the same MRays/s.  The fraction is exact and repeatable; MRays/s is timed, hence noisy on a shared
// machine: both are reported, and `repeats` renders every configuration (the reference included) that
// many times round-robin, so that a change of load falls on all of them alike, and takes the median.
#pragma once

#include "common/render/render_types.h"
#include "validate/measure.h"
#include "validate/rmse_study.h"
#include "validate/table.h"

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace ls {

struct PolicyPoint {
  std::string policy;     // "bounce" or "throughput"
  int start_bounce = 0;   // bounce policy: X from this bounce on
  float threshold = 0.0f; // throughput policy: X below this throughput luminance
  double rmse = 0.0;
  std::vector<double> contribution_rmse;  // per bounce 0..B
  BiasEstimate bias;                      // rmse_bias, its standard error, the noise floor
  int spp = 0;
  std::string spp_stop;                   // --spp auto: why it stopped adding samples
  double mrays_per_s = 0.0;
  uint64_t rays_on_x = 0, indirect_rays = 0;
  double fraction_on_x() const { return indirect_rays ? double(rays_on_x) / double(indirect_rays) : 0.0; }
  std::string label() const;  // "from bounce 2", "T = 0.3"
};

// One bounce-policy point beside the throughput policy at the same fraction of rays on X and at the
// same MRays/s (NaN: outside the range the thresholds cover; no extrapolation).
struct PolicyComparison {
  int start_bounce = 0;
  double fraction_on_x = 0.0, mrays_per_s = 0.0, bounce_rmse = 0.0;
  double throughput_rmse_at_fraction = 0.0, threshold_at_fraction = 0.0;
  double throughput_rmse_at_speed = 0.0, threshold_at_speed = 0.0;
  // The same on rmse_bias (NaN without an estimate): the comparison that does not move with spp.
  double bounce_rmse_bias = 0.0, throughput_rmse_bias_at_fraction = 0.0, throughput_rmse_bias_at_speed = 0.0;
};

struct PolicyStudy {
  std::string scene, device, structure;
  ImageSettings settings;
  int repeats = 3;                  // timed renders per configuration (median MRays/s)
  double reference_mrays_per_s = 0.0;
  size_t reference_bytes = 0, structure_bytes = 0;
  std::vector<PolicyPoint> points;  // bounce policy by start bounce, then throughput policy by T
  std::vector<PolicyComparison> comparisons;

  Table points_table() const;
  Table comparison_table() const;
  std::string markdown() const;
  nlohmann::json json() const;
};

// y at x on the polyline through the (x, y) points taken in order of x (equal x: the first given);
// NaN when x lies outside [min x, max x] or there are no points.
double interpolate(std::vector<std::pair<double, double>> points, double x);

// Indirect rays (bounces >= 1) of a render, and those of them traced with `structure` (schedule
// entries that are it, and the switched rays when the throughput switch's structure is it).
void rays_on_structure(const RenderResult& result, const std::string& structure, const ThroughputSwitch& throughput_switch,
                       uint64_t& on_structure, uint64_t& indirect);

// The comparisons of the study's points.  The throughput policy's curve includes T -> 0, which
// switches nothing and so is the reference (fraction 0, RMSE 0, the reference's MRays/s).
std::vector<PolicyComparison> compare_policies(const PolicyStudy& study);

// thresholds: each finite and > 0 (parse_switch_threshold); start bounces in [1, settings.bounces].
PolicyStudy run_policy_study(StudyRenderer& renderer, const std::string& scene, const StructureSpec& structure,
                             const std::vector<int>& start_bounces, const std::vector<float>& thresholds,
                             const ImageSettings& settings, const Log& log, int repeats = 3);

// policy.md (both tables), policy.csv (every configuration), policy.json into dir.
void write_policy_study(const std::string& dir, const PolicyStudy& study);

// "0.1,0.3": each a finite number > 0, sorted, repeats dropped; throws InputError naming --thresholds.
std::vector<float> parse_threshold_list(const std::string& text);

}  // namespace ls
