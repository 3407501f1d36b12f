#include "render_output.h"

#include "bench.h"
#include "image_output.h"
#include "interrupt.h"

#include <tbb/info.h>

#include <filesystem>
#include <fstream>

namespace ls {

nlohmann::json render_report(const RenderResult& result, const RenderReportContext& context) {
  using nlohmann::json;
  json per_bounce = json::array();
  for (size_t k = 0; k < result.bounces.size(); ++k) {
    const BounceStats& b = result.bounces[k];
    const uint64_t rays = b.extension_rays + b.shadow_rays;
    per_bounce.push_back({{"bounce", k},
                          {"structure", b.structure},
                          {"extension_rays", b.extension_rays},
                          {"shadow_rays", b.shadow_rays},
                          {"rays", rays},
                          {"seconds", b.trace_seconds},
                          {"ls_lookups", b.ls.lookups},
                          {"ls_empty", b.ls.empty},
                          {"ls_accepted", b.ls.accepted},
                          {"ls_refused_angle", b.ls.refused_angle},
                          {"ls_refused_behind", b.ls.refused_behind},
                          {"ls_refused_beyond", b.ls.refused_beyond},
                          {"ls_refused_parallel", b.ls.refused_parallel},
                          {"ls_refused_no_shaft", b.ls.refused_no_shaft},
                          {"mrays_per_s", b.trace_seconds > 0.0 ? double(rays) / b.trace_seconds * 1e-6 : 0.0}});
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
              {"threads", tbb::info::default_concurrency()},
              {"seconds", result.seconds},
              {"primary", {{"rays", primary.extension_rays + primary.shadow_rays}, {"seconds", primary.trace_seconds}}},
              {"indirect",
               {{"rays", result.indirect_rays()},
                {"seconds", result.indirect_seconds()},
                {"mrays_per_s", result.indirect_mrays_per_s()}}},
              {"per_bounce", per_bounce},
              {"structures", structures},
              {"dropped_samples", result.dropped_samples}};
  if (!context.frame.is_null()) report["frame"] = context.frame;
  return report;
}

nlohmann::json write_render_outputs(const std::string& dir, const RenderResult& result, const RenderReportContext& context) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create output folder '" + dir + "': " + ec.message());
  const std::filesystem::path out(dir);
  Image image{result.width, result.height, result.total};
  write_exr((out / "total.exr").string(), image);
  write_png((out / "image.png").string(), image);
  for (size_t k = 0; k < result.bounce_images.size(); ++k)
    write_exr((out / ("bounce_" + std::to_string(k) + ".exr")).string(),
              Image{result.width, result.height, result.bounce_images[k]});
  nlohmann::json report = render_report(result, context);
  const std::string path = (out / "report.json").string(), temp = path + ".partial";
  throw_if_interrupted();
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
  std::filesystem::rename(temp, path);
  set_partial_file(nullptr);
  return report;
}

}  // namespace ls
