// `linespace-validate rmse`: the paper's Table 3 on one scene.  The all-exact reference is rendered
// once; then, for each structure S and start bounce k = 1..B, the image with the exact F-BVH before
// bounce k and S from k on, with the same random numbers.  Speed is the MRays/s of bounces >= 1 with
// S from bounce 1, beside the reference's in the same run.  Each row carries the RMSE (all samples,
// noise included) and rmse_bias (the approximation's own error, measure.h) with its standard error.
#pragma once

#include "validate/measure.h"
#include "validate/table.h"

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ls {

// The figures of MeasuredFigures and of the structure as built (BuiltFigures::bytes: the
// structure's own); the speed-up is over the exact F-BVH timed beside this row.
struct RmseRow : MeasuredFigures, BuiltFigures {
  std::string structure;
  int start_bounce = 1;
  std::vector<double> contribution_rmse;  // per bounce 0..B
  std::string refused;                    // non-empty: not built (the reason), no figures
};

struct RmseStudy {
  std::string scene, device;
  ImageSettings settings;
  double reference_mrays_per_s = 0.0;
  size_t reference_bytes = 0;
  std::vector<RmseRow> rows;

  const RmseRow* find(const std::string& structure, int start_bounce) const;
  Table summary() const;  // Table 3: one line per structure (RMSE and rmse_bias per start bounce)
  Table detail() const;   // one line per structure and start bounce, with per-bounce contributions
  std::string markdown() const;  // rmse.md: the summary, then per row the spp, rmse_bias and noise floor
  nlohmann::json json() const;
};

using Log = std::function<void(const std::string&)>;

// out_dir non-empty: writes the reference PNG and, per structure and start bounce, a heat-map and
// the images side by side (heat-map scale: error `heatmap_max` is the top of the ramp).
// release_structures: each structure is freed once its rows are measured (long lists of big ones).
RmseStudy run_rmse_study(StudyRenderer& renderer, const std::string& scene, const std::vector<StructureSpec>& structures,
                         const ImageSettings& settings, const std::string& out_dir, float heatmap_max, const Log& log,
                         bool release_structures = false);

// rmse.md (the summary, then the detail's noise floors), rmse.csv (detail), rmse.json into dir.
void write_rmse_study(const std::string& dir, const RmseStudy& study);

std::string file_safe(const std::string& structure);  // f-ls:8:6 -> f-ls_8_6

}  // namespace ls
