#include "validate/rmse_study.h"

#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "validate/heatmap.h"

#include <chrono>
#include <cmath>
#include <filesystem>

namespace ls {

namespace {

Image as_image(const RenderResult& r, const std::vector<glm::vec3>& pixels) { return Image{r.width, r.height, pixels}; }

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

std::string file_safe(const std::string& structure) {
  std::string s = structure;
  for (char& c : s)
    if (c == ':' || c == ',' || c == '(' || c == ')') c = '_';
  return s;
}

const RmseRow* RmseStudy::find(const std::string& structure, int start_bounce) const {
  for (const RmseRow& r : rows)
    if (r.structure == structure && r.start_bounce == start_bounce) return &r;
  return nullptr;
}

Table RmseStudy::summary() const {
  Table t;
  t.header = {"structure", "MRays/s", "speed-up vs F-BVH", "MB"};
  for (int k = 1; k <= settings.bounces; ++k) t.header.push_back("RMSE from bounce " + std::to_string(k));
  for (int k = 1; k <= settings.bounces; ++k) t.header.push_back("rmse_bias from bounce " + std::to_string(k));
  t.rows.push_back({"bvh (reference)", fixed(reference_mrays_per_s, 2), "1.00", fixed(double(reference_bytes) / 1e6, 1)});
  for (int k = 1; k <= 2 * settings.bounces; ++k) t.rows.back().push_back("-");
  for (const RmseRow& r : rows) {
    if (r.start_bounce != 1) continue;
    std::vector<std::string> line = {r.structure};
    if (!r.refused.empty()) {
      line.push_back("refused: " + r.refused);
      while (line.size() < t.header.size()) line.push_back("-");
    } else {
      line.push_back(fixed(r.mrays_per_s, 2));
      line.push_back(fixed(r.speedup, 2));
      line.push_back(fixed(double(r.bytes) / 1e6, 1));
      for (int k = 1; k <= settings.bounces; ++k) {
        const RmseRow* at = find(r.structure, k);
        line.push_back(at ? rmse_text(at->rmse) : "-");
      }
      for (int k = 1; k <= settings.bounces; ++k) {
        const RmseRow* at = find(r.structure, k);
        line.push_back(at ? bias_text(at->bias) : "-");
      }
    }
    t.rows.push_back(line);
  }
  return t;
}

Table RmseStudy::detail() const {
  Table t;
  t.header = {"structure", "start_bounce", "rmse", "rmse_bias", "rmse_bias_stderr", "noise_floor", "spp", "spp_stop",
              "mrays_per_s", "bytes"};
  for (int k = 0; k <= settings.bounces; ++k) t.header.push_back("contribution_rmse_bounce_" + std::to_string(k));
  t.header.push_back("refused");
  for (const RmseRow& r : rows) {
    std::vector<std::string> line = {r.structure, std::to_string(r.start_bounce)};
    const bool ok = r.refused.empty();
    line.push_back(ok ? fixed(r.rmse, 6) : "");
    line.push_back(ok ? fixed(r.bias.rmse_bias, 6) : "");
    line.push_back(ok ? fixed(r.bias.rmse_bias_stderr, 6) : "");
    line.push_back(ok ? fixed(r.bias.noise_floor, 6) : "");
    line.push_back(ok ? std::to_string(r.spp) : "");
    line.push_back(r.spp_stop);
    line.push_back(ok ? fixed(r.mrays_per_s, 4) : "");
    line.push_back(ok ? std::to_string(r.bytes) : "");
    for (int k = 0; k <= settings.bounces; ++k)
      line.push_back(ok && size_t(k) < r.contribution_rmse.size() ? fixed(r.contribution_rmse[size_t(k)], 6) : "");
    line.push_back(r.refused);
    t.rows.push_back(line);
  }
  return t;
}

std::string RmseStudy::markdown() const {
  Table t;
  t.header = {"structure", "start bounce", "spp", "RMSE", "rmse_bias ± stderr", "noise floor"};
  if (settings.auto_spp.enabled) t.header.push_back("--spp auto stopped");
  for (const RmseRow& r : rows) {
    if (!r.refused.empty()) continue;
    t.rows.push_back({r.structure, std::to_string(r.start_bounce), std::to_string(r.spp), rmse_text(r.rmse),
                      bias_text(r.bias), rmse_text(r.bias.noise_floor)});
    if (settings.auto_spp.enabled) t.rows.back().push_back(r.spp_stop);
  }
  return summary().markdown() +
         "\nRMSE: all samples, sampling noise included; rmse_bias: the error of the expected images, from two "
         "independent halves of the samples, ± one standard error (docs/design.md §7). The heat-maps show the per-pixel "
         "difference of the images averaged over both halves; the noise floor is the RMS of the sampling noise in that "
         "difference (RMSE² ≈ rmse_bias² + noise floor²).\n\n" +
         t.markdown();
}

nlohmann::json RmseStudy::json() const {
  nlohmann::json rows_json = nlohmann::json::array();
  for (const RmseRow& r : rows) {
    nlohmann::json j{{"structure", r.structure}, {"start_bounce", r.start_bounce}};
    if (!r.refused.empty()) {
      j["refused"] = r.refused;
    } else if (r.spp == 0) {  // built, never rendered (paper --tables 2): no figures of a render, not zeros
      for (const char* key : {"rmse", "rmse_bias", "rmse_bias_stderr", "noise_floor", "spp", "mrays_per_s",
                              "exact_mrays_per_s", "speedup_vs_bvh", "contribution_rmse"})
        j[key] = nullptr;
      j["bytes"] = r.bytes;
      j["bytes_ls"] = r.bytes_ls;
      j["ls_nodes"] = r.ls_nodes;
      j["build_seconds"] = r.build_seconds;
    } else {
      j["rmse"] = r.rmse;
      j["rmse_bias"] = number_or_null(r.bias.rmse_bias);
      j["rmse_bias_stderr"] = number_or_null(r.bias.rmse_bias_stderr);
      j["noise_floor"] = number_or_null(r.bias.noise_floor);
      j["spp"] = r.spp;
      if (!r.spp_stop.empty()) j["spp_stop"] = r.spp_stop;
      j["mrays_per_s"] = r.mrays_per_s;
      j["exact_mrays_per_s"] = r.exact_mrays_per_s;
      j["speedup_vs_bvh"] = r.speedup;
      j["bytes"] = r.bytes;
      j["bytes_ls"] = r.bytes_ls;
      j["ls_nodes"] = r.ls_nodes;
      j["build_seconds"] = r.build_seconds;
      j["contribution_rmse"] = r.contribution_rmse;
    }
    rows_json.push_back(j);
  }
  nlohmann::json j = study_json(scene, device, settings, reference_mrays_per_s, reference_bytes);
  j["rows"] = rows_json;
  return j;
}

RmseStudy run_rmse_study(StudyRenderer& renderer, const std::string& scene, const std::vector<StructureSpec>& structures,
                         const ImageSettings& settings, const std::string& out_dir, float heatmap_max, const Log& log,
                         bool release_structures) {
  RmseStudy study;
  study.scene = scene;
  study.device = renderer.device();
  study.settings = settings;
  if (!out_dir.empty()) std::filesystem::create_directories(out_dir);

  auto t0 = std::chrono::steady_clock::now();
  Reference reference = render_reference(renderer, settings);
  study.reference_mrays_per_s = reference.result.indirect_mrays_per_s();
  study.reference_bytes = reference.bytes;
  log("reference (bvh): " + fixed(seconds_since(t0), 2) + " s, " + fixed(study.reference_mrays_per_s, 2) + " MRays/s");
  const Image ref_image = as_image(reference.result, reference.result.total);
  if (!out_dir.empty()) write_png(out_dir + "/reference.png", ref_image, reference.scale);

  const size_t total = structures.size() * size_t(settings.bounces);
  size_t done = 0;
  for (const StructureSpec& spec : structures) {
    std::string refused;
    RmseRow built;
    try {
      static_cast<BuiltFigures&>(built) = built_figures(renderer.structure(spec));
    } catch (const InputError& e) {
      refused = e.what();
      log(spec.name() + ": refused: " + refused);
    }
    for (int k = 1; k <= settings.bounces; ++k) {
      RmseRow row = built;
      row.structure = spec.name();
      row.start_bounce = k;
      ++done;
      if (!refused.empty()) {
        row.refused = refused;
        study.rows.push_back(row);
        continue;
      }
      t0 = std::chrono::steady_clock::now();
      const Measured m = measure(renderer, schedule_from(spec, k), settings, reference);
      static_cast<MeasuredFigures&>(row) = m;
      row.contribution_rmse = m.contribution_rmse;
      study.rows.push_back(row);
      std::string line = "[" + std::to_string(done) + "/" + std::to_string(total) + "] " + row.structure +
                         " from bounce " + std::to_string(k) + ": RMSE " + rmse_text(row.rmse) + ", rmse_bias " +
                         bias_text(row.bias) + ", noise floor " + rmse_text(row.bias.noise_floor);
      line += " (" + spp_text(m) + "), " + fixed(row.mrays_per_s, 2) + " MRays/s, ";
      line += fixed(row.speedup, 2) + "x F-BVH beside it, " + fixed(seconds_since(t0), 2) + " s";
      log(line);
      // The heat-map shows the difference of the images averaged over both halves (all samples).
      if (!out_dir.empty())
        write_error_images(out_dir + "/" + file_safe(row.structure) + "_from_bounce_" + std::to_string(k),
                           Image{m.result.width, m.result.height, m.reference_total}, as_image(m.result, m.result.total),
                           reference.scale, heatmap_max);
    }
    if (release_structures) renderer.release(spec);
  }
  return study;
}

void write_rmse_study(const std::string& dir, const RmseStudy& study) {
  std::filesystem::create_directories(dir);
  write_text_file(dir + "/rmse.md", study.markdown());
  write_text_file(dir + "/rmse.csv", study.detail().csv());
  write_text_file(dir + "/rmse.json", study.json().dump(2) + "\n");
}

}  // namespace ls
