// What `render` leaves in its output folder: total.exr, bounce_K.exr for each bounce (linear),
// image.png (sRGB, exposed (exposure.h) and clamped), and report.json with rays and seconds per bounce
// and the exposure used.
#pragma once

#include "common/render/exposure.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"

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
  ThroughputSwitch throughput_switch;  // off: the report's "throughput_switch" is null
  ExposureRequest exposure;  // the PNG's (write_render_outputs reports what it used)
};

nlohmann::json render_report(const RenderResult& result, const RenderReportContext& context);
// Writes every file into `dir` (created if missing); returns the report that was written (with
// "exposure": exposure_json of the PNG's).
nlohmann::json write_render_outputs(const std::string& dir, const RenderResult& result, const RenderReportContext& context);

// The parts of write_render_outputs: the folder, the images (total.exr, bounce_K.exr, image.png) and
// a JSON file, each written to a temporary name and renamed (interrupt.h).  A pending interrupt stops
// a JSON file before it starts, unless `while_interrupted` (the last listing of a stopped run).
void create_output_folder(const std::string& dir);
void write_render_images(const std::string& dir, const RenderResult& result, const Exposure& exposure);
void write_json_file(const std::string& path, const nlohmann::json& json, bool while_interrupted = false);

// Line Space counters as report keys: prefix + lookups, empty, accepted, refused_angle, ...
void put_ls_counters(nlohmann::json& into, const std::string& prefix, const lsk::LsCounters& counters);
lsk::LsCounters get_ls_counters(const nlohmann::json& from, const std::string& prefix);  // throws json errors

}  // namespace ls
