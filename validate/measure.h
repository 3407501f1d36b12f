// One measurement of the validator: render a schedule with the same random numbers as the all-exact
// reference and compare (docs/design.md §6–7).  The RMSE of the total image is the figure the paper reports;
// the RMSE of each bounce's own contribution shows where the error comes from.
#pragma once

#include "common/render/render_types.h"
#include "cpu/render/path_tracer.h"
#include "validate/study_renderer.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace ls {

struct ImageSettings {
  uint32_t width = 256, height = 256;
  int spp = 4;
  int bounces = 3;
  uint32_t seed = 1;
  LsLookup lookup;  // --ls-angle, --ls-behind: every render's Line Space lookups
  RenderOptions options(const Schedule& schedule) const;
};

struct Reference {
  RenderResult result;  // the all-exact (F-BVH) render
  float scale = 1.0f;   // e of docs/design.md §7, from its total image
  size_t bytes = 0;
};

struct Measured {
  std::string schedule;
  double rmse = 0.0;                      // total image
  std::vector<double> contribution_rmse;  // bounce 0..B images
  double mrays_per_s = 0.0;               // rays of bounces >= 1 per second of tracing
  size_t bytes = 0;                       // distinct structures of the schedule
  RenderResult result;
};

Reference render_reference(StudyRenderer& renderer, const ImageSettings& settings);
Measured measure(StudyRenderer& renderer, const Schedule& schedule, const ImageSettings& settings,
                 const Reference& reference);
// The same for any render options (a throughput switch, say); bytes: every structure the render uses.
Measured measure(StudyRenderer& renderer, const RenderOptions& options, const Reference& reference);

// What every study's JSON opens with: the scene, the device, the image settings and the reference.
nlohmann::json study_json(const std::string& scene, const std::string& device, const ImageSettings& settings,
                          double reference_mrays_per_s, size_t reference_bytes);

}  // namespace ls
