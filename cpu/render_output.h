// What `render` leaves in its output folder: total.exr, bounce_K.exr for each bounce (linear),
// image.png (sRGB, tone-mapped by clamping), and report.json with rays and seconds per bounce.
#pragma once

#include "path_tracer.h"

#include <nlohmann/json.hpp>
#include <string>

namespace ls {

struct RenderReportContext {
  std::string scene;
  std::string schedule;
  int spp = 0;
  uint32_t seed = 0;
  const std::map<std::string, Accel>* structures = nullptr;
  std::string device;  // who traced: empty for this CPU ("cpu: MODEL" in the report)
  nlohmann::json frame;  // render --frames: this frame's index, time and updates (key "frame"); null: none
};

nlohmann::json render_report(const RenderResult& result, const RenderReportContext& context);
// Writes every file into `dir` (created if missing); returns the report that was written.
nlohmann::json write_render_outputs(const std::string& dir, const RenderResult& result, const RenderReportContext& context);

}  // namespace ls
