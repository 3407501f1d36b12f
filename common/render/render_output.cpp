#include "common/render/render_output.h"

#include "common/base/interrupt.h"
#include "common/base/replace_file.h"
#include "common/base/system_info.h"
#include "common/base/thread_limit.h"
#include "common/render/image_output.h"
#include "common/render/render_types.h"

#include <filesystem>
#include <fstream>

namespace ls {

namespace {

// The report's name of each Line Space counter (after a prefix such as "ls_").
struct CounterKey {
  const char* name;
  uint32_t lsk::LsCounters::*field;
};
constexpr CounterKey kCounterKeys[] = {
    {"lookups", &lsk::LsCounters::lookups},
    {"empty", &lsk::LsCounters::empty},
    {"accepted", &lsk::LsCounters::accepted},
    {"refused_angle", &lsk::LsCounters::refused_angle},
    {"refused_behind", &lsk::LsCounters::refused_behind},
    {"refused_beyond", &lsk::LsCounters::refused_beyond},
    {"refused_parallel", &lsk::LsCounters::refused_parallel},
    {"refused_no_shaft", &lsk::LsCounters::refused_no_shaft},
};

}  // namespace

void put_ls_counters(nlohmann::json& into, const std::string& prefix, const lsk::LsCounters& c) {
  for (const CounterKey& k : kCounterKeys) into[prefix + k.name] = c.*k.field;
}

lsk::LsCounters get_ls_counters(const nlohmann::json& from, const std::string& prefix) {
  lsk::LsCounters c{};
  for (const CounterKey& k : kCounterKeys) c.*k.field = from.at(prefix + k.name).get<uint32_t>();
  return c;
}

nlohmann::json render_report(const RenderResult& result, const RenderReportContext& context) {
  using nlohmann::json;
  json per_bounce = json::array();
  for (size_t k = 0; k < result.bounces.size(); ++k) {
    const BounceStats& b = result.bounces[k];
    const uint64_t rays = b.extension_rays + b.shadow_rays;
    json entry{{"bounce", k},
               {"structure", b.structure},
               {"extension_rays", b.extension_rays},
               {"shadow_rays", b.shadow_rays},
               {"rays", rays},
               {"seconds", b.trace_seconds}};
    put_ls_counters(entry, "ls_", b.ls);
    entry["mrays_per_s"] = b.trace_seconds > 0.0 ? double(rays) / b.trace_seconds * 1e-6 : 0.0;
    // The part of the above that the throughput switch traced with its structure.
    entry["switched_extension_rays"] = b.switched_extension_rays;
    entry["switched_shadow_rays"] = b.switched_shadow_rays;
    entry["switched_rays"] = b.switched_extension_rays + b.switched_shadow_rays;
    entry["switched_seconds"] = b.switched_seconds;
    put_ls_counters(entry, "switched_ls_", b.switched_ls);
    per_bounce.push_back(entry);
  }
  json structures = json::array();
  if (context.structures)
    for (const auto& [name, accel] : *context.structures)
      structures.push_back({{"structure", name},
                            {"build_seconds", accel.build_seconds},
                            {"bytes_total", accel.bytes_total()},
                            {"bytes_ls", accel.bytes_ls()},
                            {"ls_nodes", accel.ls_info.ls_nodes},
                            {"shafts_per_ls", accel.ls_info.shafts_per_ls}});
  const BounceStats& primary = result.bounces.front();
  json report{{"scene", context.scene},
              {"schedule", context.schedule},
              {"width", result.width},
              {"height", result.height},
              {"spp", context.spp},
              {"bounces", int(result.bounces.size()) - 1},
              {"seed", context.seed},
              {"device", context.device.empty() ? "cpu: " + cpu_model() : context.device},
              {"threads", thread_count()},
              {"seconds", result.seconds},
              {"primary", {{"rays", primary.extension_rays + primary.shadow_rays}, {"seconds", primary.trace_seconds}}},
              {"indirect",
               {{"rays", result.indirect_rays()},
                {"seconds", result.indirect_seconds()},
                {"mrays_per_s", result.indirect_mrays_per_s()}}},
              {"per_bounce", per_bounce},
              {"structures", structures},
              {"dropped_samples", result.dropped_samples},
              {"throughput_switch", context.throughput_switch.enabled()
                                        ? json{{"threshold", std::stod(shortest_text(context.throughput_switch.threshold))},
                                               {"structure", context.throughput_switch.structure.name()}}
                                        : json(nullptr)}};
  if (!context.frame.is_null()) report["frame"] = context.frame;
  return report;
}

void create_output_folder(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create output folder '" + dir + "': " + ec.message());
}

void write_render_images(const std::string& dir, const RenderResult& result, const Exposure& exposure) {
  create_output_folder(dir);
  const std::filesystem::path out(dir);
  Image image{result.width, result.height, result.total};
  write_exr((out / "total.exr").string(), image);
  write_png((out / "image.png").string(), image, exposure.multiplier);
  for (size_t k = 0; k < result.bounce_images.size(); ++k)
    write_exr((out / ("bounce_" + std::to_string(k) + ".exr")).string(),
              Image{result.width, result.height, result.bounce_images[k]});
}

nlohmann::json write_render_outputs(const std::string& dir, const RenderResult& result, const RenderReportContext& context) {
  const Exposure exposure = choose_exposure(context.exposure, result.total);
  write_render_images(dir, result, exposure);
  nlohmann::json report = render_report(result, context);
  report["exposure"] = exposure_json(exposure);
  write_json_file((std::filesystem::path(dir) / "report.json").string(), report);
  return report;
}

void write_json_file(const std::string& path, const nlohmann::json& report, bool while_interrupted) {
  const std::string temp = path + ".partial";
  if (!while_interrupted) throw_if_interrupted();
  set_partial_file(&temp);
  {
    std::ofstream f(temp);
    f << report.dump(2) << "\n";
    if (!f) {
      set_partial_file(nullptr);
      std::error_code ec;
      std::filesystem::remove(temp, ec);
      throw InputError("cannot write '" + path + "'");
    }
  }
  replace_file(temp, path);
}

}  // namespace ls
