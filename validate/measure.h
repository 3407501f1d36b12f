// One measurement of the validator: render a schedule with the same random numbers as the all-exact
// reference and compare (docs/design.md §6–7).  Both are rendered as two disjoint sample halves
// (split_render.h): `rmse` compares the halves combined (all samples; it carries sampling noise once
// the paths diverge), `bias` estimates the error of the expected images from the halves
// (bias_estimate.h).  The RMSE of the total image is the figure the paper reports; the RMSE of each
// bounce's own contribution shows where the error comes from.
#pragma once

#include "common/render/render_types.h"
#include "cpu/render/path_tracer.h"
#include "validate/bias_estimate.h"
#include "validate/split_render.h"
#include "validate/study_renderer.h"

#include <nlohmann/json.hpp>

#include <deque>
#include <string>
#include <vector>

namespace ls {

// --spp auto: each configuration doubles its samples until rmse_bias_stderr <= rel_stderr * rmse_bias,
// or until the next doubling would, at the pace so far, end past `seconds`, or would pass max_spp.
struct SppAuto {
  bool enabled = false;
  double rel_stderr = 0.1;
  double seconds = 60.0;  // per configuration, its reference's extra samples included
  int max_spp = 1 << 16;
  nlohmann::json json() const;  // null when off
};

struct ImageSettings {
  uint32_t width = 256, height = 256;
  int spp = 4;  // with auto: the count every configuration starts from
  int bounces = 3;
  uint32_t seed = 1;
  LsLookup lookup;  // --ls-angle, --ls-behind: every render's Line Space lookups
  SppAuto auto_spp;
  // --timing-rounds: rounds of a configuration's render and the exact F-BVH's, one right after the
  // other, whose median ratio is its speed-up (Measured).  3: on a shared 2-core host single renders
  // of a 128x128, 8 spp sweep moved 2.4x between configurations, more than any Line Space's effect.
  int timing_rounds = 3;
  RenderOptions options(const Schedule& schedule) const;
};

struct Reference {
  RenderResult result;  // the all-exact (F-BVH) render at the settings' spp (both halves combined)
  float scale = 1.0f;   // e of docs/design.md §7, from its total image (with --spp auto: at the starting spp)
  size_t bytes = 0;
  RenderOptions options;           // what renders it
  // The settings' (ImageSettings::timing_rounds); 0: no timing beside the exact F-BVH, the study
  // times its configurations itself (policy's round-robin --repeat).
  int timing_rounds = 1;
  std::deque<SplitRender> levels;  // at spp, 2 spp, 4 spp, ... (more than one only with --spp auto)
  // The reference over samples 0 .. total - 1 (total: spp times a power of 2), rendered when first asked.
  const SplitRender& at(StudyRenderer& renderer, int total);
};

// What a study row keeps of one measurement: its figures without its images.  The row types of
// rmse, sweep and paper derive from it, so that a row takes them in one assignment.
struct MeasuredFigures {
  double rmse = 0.0;        // total image, all samples
  BiasEstimate bias;        // total image: rmse_bias, its standard error, the noise floor
  int spp = 0;              // samples per pixel the figures rest on
  std::string spp_stop;     // --spp auto: "converged", "time budget" or "max spp"; else empty
  // Speed: rays of bounces >= 1 per second of tracing, the medians over the timing rounds of this
  // configuration's render and of the exact F-BVH's on the same options and spp, rendered right
  // after it; the speed-up is the median of the rounds' ratios.  (The reference's own timing, once at
  // the start of a study, carried its warm-up and the machine's drift into every ratio: a fireplace
  // sweep at 8 spp put Line Spaces with no error at 1.45x the F-BVH.)
  double mrays_per_s = 0.0;
  double exact_mrays_per_s = 0.0;
  double speedup = 0.0;
};

struct Measured : MeasuredFigures {
  std::string schedule;
  std::vector<double> contribution_rmse;  // bounce 0..B images
  size_t bytes = 0;                       // distinct structures of the schedule
  RenderResult result;                    // both halves combined
  std::vector<glm::vec3> reference_total; // the reference's total image at the same spp (heat-maps)
};

Reference render_reference(StudyRenderer& renderer, const ImageSettings& settings);
Measured measure(StudyRenderer& renderer, const Schedule& schedule, const ImageSettings& settings, Reference& reference);
// The same for any render options (a throughput switch, say); bytes: every structure the render uses.
Measured measure(StudyRenderer& renderer, const RenderOptions& options, Reference& reference,
                 const SppAuto& auto_spp = {});

// "converged" etc. with the spp, for the log: "32 spp, converged".
std::string spp_text(const Measured& m);
// ".0101 ± .0008", or "-" without an estimate.
std::string bias_text(const BiasEstimate& b);

// What every study's JSON opens with: the scene, the device, the image settings and the reference.
nlohmann::json study_json(const std::string& scene, const std::string& device, const ImageSettings& settings,
                          double reference_mrays_per_s, size_t reference_bytes);
// A number, or null for NaN (no estimate).
nlohmann::json number_or_null(double v);

}  // namespace ls
