#include "validate/sweep.h"

#include "common/structure/accel.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

namespace ls {

namespace {

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) parts.push_back(item);
  if (parts.empty() || text.empty() || text.back() == ',') throw InputError("empty item in list '" + text + "'");
  return parts;
}

}  // namespace

std::vector<int> parse_int_list(const std::string& text, const std::string& flag, int lo, int hi) {
  std::vector<int> out;
  for (const std::string& item : split(text)) {
    size_t used = 0;
    long v = 0;
    try {
      v = std::stol(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || v < lo || v > hi)
      throw InputError(flag + " " + text + ": '" + item + "' is not an integer in [" + std::to_string(lo) + ", " +
                       std::to_string(hi) + "]");
    out.push_back(int(v));
  }
  return without_repeats(out);
}

std::vector<float> parse_angle_list(const std::string& text) {
  std::vector<float> out;
  for (const std::string& item : split(text)) {
    size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !(v >= 0.0 && v <= 90.0))
      throw InputError("--angles " + text + ": '" + item + "' is not an angle in [0, 90] degrees");
    out.push_back(float(v));
  }
  return without_repeats(out);
}

std::vector<LsBehind> parse_behind_list(const std::string& text) {
  std::vector<LsBehind> out;
  for (const std::string& item : split(text)) {
    try {
      out.push_back(parse_ls_behind(item));
    } catch (const InputError&) {
      throw InputError("--behinds " + text + ": '" + item + "' is not a mode (exact, empty or reverse)");
    }
  }
  return without_repeats(out);
}

std::vector<uint32_t> parse_min_triangles_list(const std::string& text) {
  std::vector<uint32_t> out;
  for (int v : parse_int_list(text, "--min-triangles", 0, std::numeric_limits<int>::max())) out.push_back(uint32_t(v));
  return out;
}

std::vector<StructureKind> parse_families(const std::string& text) {
  std::vector<StructureKind> out;
  for (const std::string& item : split(text)) {
    if (item == "f-ls") out.push_back(StructureKind::FlatLs);
    else if (item == "2l-ls") out.push_back(StructureKind::TwoLevelLs);
    else throw InputError("--families " + text + ": '" + item + "' is neither f-ls nor 2l-ls");
  }
  return without_repeats(out);
}

namespace {

double error_of(const SweepPoint& p) { return p.bias.valid() ? p.bias.rmse_bias : p.rmse; }

}  // namespace

void mark_pareto(std::vector<SweepPoint>& points) {
  for (SweepPoint& p : points) {
    p.pareto = p.refused.empty() && !(1.0 >= p.speedup && (1.0 > p.speedup || error_of(p) > 0.0));
    for (const SweepPoint& q : points) {
      if (&q == &p || !q.refused.empty() || !p.pareto) continue;
      const bool as_good = q.speedup >= p.speedup && error_of(q) <= error_of(p);
      const bool better = q.speedup > p.speedup || error_of(q) < error_of(p);
      if (as_good && better) p.pareto = false;
    }
  }
}

Table Sweep::table() const {
  Table t;
  t.header = {"structure", "depth", "subdivision", "angle", "behind", "min_triangles", "rmse", "rmse_bias", "rmse_bias_stderr", "noise_floor", "spp",
              "spp_stop", "mrays_per_s", "exact_mrays_per_s", "speedup_vs_bvh", "bytes", "bytes_ls", "ls_nodes", "build_seconds", "pareto",
              "refused"};
  for (const SweepPoint& p : points) {
    const bool ok = p.refused.empty();
    t.rows.push_back({p.structure, std::to_string(p.depth), std::to_string(p.subdivision), fixed(p.angle, 1),
                      ls_behind_name(p.behind), std::to_string(p.min_triangles),
                      ok ? fixed(p.rmse, 6) : "", ok ? fixed(p.bias.rmse_bias, 6) : "",
                      ok ? fixed(p.bias.rmse_bias_stderr, 6) : "", ok ? fixed(p.bias.noise_floor, 6) : "",
                      ok ? std::to_string(p.spp) : "", p.spp_stop,
                      ok ? fixed(p.mrays_per_s, 4) : "", ok ? fixed(p.exact_mrays_per_s, 4) : "",
                      ok ? fixed(p.speedup, 4) : "",
                      ok ? std::to_string(p.bytes) : "", ok ? std::to_string(p.bytes_ls) : "",
                      ok ? std::to_string(p.ls_nodes) : "", ok ? fixed(p.build_seconds, 3) : "",
                      p.pareto ? "1" : "0", p.refused});
  }
  return t;
}

nlohmann::json Sweep::json() const {
  nlohmann::json pts = nlohmann::json::array();
  for (const SweepPoint& p : points) {
    nlohmann::json j{{"structure", p.structure}, {"depth", p.depth}, {"subdivision", p.subdivision},
                     {"angle", p.angle}, {"behind", ls_behind_name(p.behind)}, {"min_triangles", p.min_triangles},
                     {"pareto", p.pareto}};
    if (p.refused.empty()) {
      j.update({{"rmse", p.rmse}, {"rmse_bias", number_or_null(p.bias.rmse_bias)},
                {"rmse_bias_stderr", number_or_null(p.bias.rmse_bias_stderr)},
                {"noise_floor", number_or_null(p.bias.noise_floor)}, {"spp", p.spp}, {"mrays_per_s", p.mrays_per_s},
                {"exact_mrays_per_s", p.exact_mrays_per_s}, {"speedup_vs_bvh", p.speedup}, {"bytes", p.bytes},
                {"bytes_ls", p.bytes_ls}, {"ls_nodes", p.ls_nodes}, {"build_seconds", p.build_seconds}});
    } else {
      j["refused"] = p.refused;
    }
    if (!p.spp_stop.empty()) j["spp_stop"] = p.spp_stop;
    pts.push_back(j);
  }
  nlohmann::json j = study_json(scene, device, settings, reference_mrays_per_s, reference_bytes);
  j["start_bounce"] = start_bounce;
  j["points"] = pts;
  return j;
}

Sweep run_sweep(StudyRenderer& renderer, const std::string& scene, const SweepGrid& grid, const ImageSettings& settings,
                const Log& log) {
  if (grid.start_bounce < 1 || grid.start_bounce > settings.bounces)
    throw InputError("--start-bounce " + std::to_string(grid.start_bounce) + " must be in [1, --bounces " +
                     std::to_string(settings.bounces) + "]");
  Sweep sweep;
  sweep.scene = scene;
  sweep.device = renderer.device();
  sweep.settings = settings;
  sweep.start_bounce = grid.start_bounce;
  Reference reference = render_reference(renderer, settings);
  sweep.reference_mrays_per_s = reference.result.indirect_mrays_per_s();
  sweep.reference_bytes = reference.bytes;
  log("reference (bvh): " + fixed(sweep.reference_mrays_per_s, 2) + " MRays/s");

  // Every point of the grid, in the order it is measured: the smallest subtree, a build option,
  // outermost; the behind mode and the angle are the lookup's and need no build of their own.
  std::vector<std::pair<StructureSpec, SweepPoint>> grid_points;
  for (uint32_t min_triangles : grid.min_triangles)
    for (LsBehind behind : grid.behinds)
      for (float angle : grid.angles)
        for (StructureKind family : grid.families)
          for (int depth : grid.depths)
            for (int n : grid.subdivisions) {
              const StructureSpec spec{family, depth, n};
              SweepPoint p;
              p.structure = spec.name();
              p.depth = depth;
              p.subdivision = n;
              p.angle = angle;
              p.behind = behind;
              p.min_triangles = min_triangles;
              grid_points.emplace_back(spec, p);
            }
  for (auto& [spec, p] : grid_points) {
    renderer.set_ls_min_triangles(p.min_triangles);
    try {
      static_cast<BuiltFigures&>(p) = built_figures(renderer.structure(spec));
    } catch (const InputError& e) {
      p.refused = e.what();
    }
    if (p.refused.empty()) {
      ImageSettings lookup = settings;
      lookup.lookup.angle_degrees = p.angle;
      lookup.lookup.behind = p.behind;
      static_cast<MeasuredFigures&>(p) = measure(renderer, schedule_from(spec, grid.start_bounce), lookup, reference);
      renderer.release(spec);
    }
    sweep.points.push_back(p);
    std::string line = "[" + std::to_string(sweep.points.size()) + "/" + std::to_string(grid_points.size()) + "] ";
    line += p.structure + " angle " + fixed(p.angle, 1);
    if (grid.behinds.size() > 1) line += std::string(" ") + ls_behind_name(p.behind);
    if (grid.min_triangles.size() > 1) line += " min-triangles " + std::to_string(p.min_triangles);
    line += ": ";
    if (p.refused.empty())
      line += "RMSE " + rmse_text(p.rmse) + ", rmse_bias " + bias_text(p.bias) + " (" + std::to_string(p.spp) + " spp" +
              (p.spp_stop.empty() ? "" : ", " + p.spp_stop) + "), " + fixed(p.speedup, 2) + "x F-BVH, " +
              fixed(double(p.bytes) / 1e6, 1) + " MB";
    else
      line += "refused: " + p.refused;
    log(line);
  }
  mark_pareto(sweep.points);
  return sweep;
}

void write_sweep(const std::string& dir, const Sweep& sweep) {
  std::filesystem::create_directories(dir);
  const Table t = sweep.table();
  write_text_file(dir + "/sweep.csv", t.csv());
  write_text_file(dir + "/sweep.md", t.markdown());
  write_text_file(dir + "/sweep.json", sweep.json().dump(2) + "\n");
}

}  // namespace ls
