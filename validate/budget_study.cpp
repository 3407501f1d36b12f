#include "validate/budget_study.h"

#include "common/structure/accel.h"
#include "cpu/app/cli_report.h"

#include <chrono>
#include <filesystem>

namespace ls {
namespace {

std::string mb(size_t bytes) { return fixed(double(bytes) / 1e6, 2); }

std::string dn(const ObjectLs& o) { return o.n > 0 ? std::to_string(o.depth) + ":" + std::to_string(o.n) : "-"; }

// Builds `spec` and measures it from every start bounce.
BudgetSide measure_side(StudyRenderer& renderer, const StructureSpec& spec, const ImageSettings& settings,
                        Reference& reference, const Log& log) {
  BudgetSide side;
  side.structure = spec.name();
  const Accel& accel = renderer.structure(spec);
  side.bytes_ls = accel.bytes_ls();
  side.build_seconds = accel.build_seconds;
  for (int k = 1; k <= settings.bounces; ++k) {
    const Measured m = measure(renderer, schedule_from(spec, k), settings, reference);
    side.rmse.push_back(m.rmse);
    side.bias.push_back(m.bias);
    side.spp.push_back(m.spp);
    side.spp_stop.push_back(m.spp_stop);
    if (k == 1) {
      side.mrays_per_s = m.mrays_per_s;
      side.speedup = m.speedup;
    }
    log("  " + side.structure + " from bounce " + std::to_string(k) + ": RMSE " + rmse_text(m.rmse) + ", rmse_bias " +
        bias_text(m.bias) + " (" + spp_text(m) + "), " + fixed(m.mrays_per_s, 2) + " MRays/s");
  }
  return side;
}

nlohmann::json side_json(const BudgetSide& s) {
  nlohmann::json bias = nlohmann::json::array(), stderr_ = nlohmann::json::array(), floor = nlohmann::json::array();
  for (const BiasEstimate& b : s.bias) {
    bias.push_back(number_or_null(b.rmse_bias));
    stderr_.push_back(number_or_null(b.rmse_bias_stderr));
    floor.push_back(number_or_null(b.noise_floor));
  }
  return {{"structure", s.structure},
          {"rmse_from_bounce", s.rmse},
          {"rmse_bias_from_bounce", bias},
          {"rmse_bias_stderr_from_bounce", stderr_},
          {"noise_floor_from_bounce", floor},
          {"spp_from_bounce", s.spp},
          {"spp_stop_from_bounce", s.spp_stop},
          {"mrays_per_s", s.mrays_per_s},
          {"speedup_vs_bvh", s.speedup},
          {"bytes_ls", s.bytes_ls},
          {"build_seconds", s.build_seconds}};
}

}  // namespace

bool BudgetComparison::lower_rmse() const {
  if (!refused.empty() || planned.rmse.size() != uniform.rmse.size() || planned.bias.size() != planned.rmse.size() ||
      uniform.bias.size() != uniform.rmse.size())
    return false;
  for (size_t k = 0; k < planned.rmse.size(); ++k) {
    const bool estimated = planned.bias[k].valid() && uniform.bias[k].valid();
    const double p = estimated ? planned.bias[k].rmse_bias : planned.rmse[k];
    const double u = estimated ? uniform.bias[k].rmse_bias : uniform.rmse[k];
    if (!(p < u)) return false;
  }
  return true;
}

BudgetStudy run_budget_study(StudyRenderer& renderer, const std::string& scene, const std::vector<StructureSpec>& uniform,
                             const ImageSettings& settings, const LsPlanOptions& plan, const Log& log) {
  for (const StructureSpec& s : uniform)
    if (s.kind != StructureKind::TwoLevelLs || s.budgeted)
      throw InputError("budget: --uniform takes 2l-ls:D:N structures, not '" + s.name() + "'");
  if (plan.budget != 0) throw InputError("budget: each comparison's budget is its uniform structure's bytes_ls; drop --ls-budget");
  BudgetStudy study;
  study.scene = scene;
  study.device = renderer.device();
  study.settings = settings;
  Reference reference = render_reference(renderer, settings);
  study.reference_mrays_per_s = reference.result.indirect_mrays_per_s();
  study.reference_bytes = reference.bytes;
  log("reference (bvh): " + fixed(study.reference_mrays_per_s, 2) + " MRays/s");
  const StructureSpec automatic = parse_structure("2l-ls:auto");
  for (const StructureSpec& spec : uniform) {
    BudgetComparison row;
    row.uniform_name = spec.name();
    try {
      row.uniform = measure_side(renderer, spec, settings, reference, log);
    } catch (const InputError& e) {
      row.refused = e.what();
      log(spec.name() + ": refused: " + row.refused);
      study.rows.push_back(row);
      continue;
    }
    row.budget = row.uniform.bytes_ls;
    LsPlanOptions budgeted = plan;
    budgeted.budget = row.budget;
    renderer.release(spec);  // the uniform structure is not held beside the planned one
    renderer.set_plan(budgeted);
    const Accel& planned = renderer.structure(automatic);
    row.plan = *planned.ls_plan;
    log("2l-ls:auto at " + mb(row.budget) + " MB: " + mb(planned.bytes_ls()) + " MB, plan in " + fixed(row.plan.seconds, 2) + " s");
    row.planned = measure_side(renderer, automatic, settings, reference, log);
    renderer.release(automatic);
    study.rows.push_back(row);
  }
  renderer.set_plan(plan);
  return study;
}

Table BudgetStudy::table() const {
  Table t;
  t.header = {"structure", "budget MB", "bytes_ls MB", "predicted MB", "MRays/s", "speed-up vs F-BVH"};
  for (int k = 1; k <= settings.bounces; ++k) t.header.push_back("RMSE from bounce " + std::to_string(k));
  for (int k = 1; k <= settings.bounces; ++k) t.header.push_back("rmse_bias from bounce " + std::to_string(k));
  t.header.insert(t.header.end(), {"pilot error", "pilot saved work", "build s", "lower rmse_bias"});
  for (const BudgetComparison& r : rows) {
    if (!r.refused.empty()) {
      std::vector<std::string> line{r.uniform_name, "refused: " + r.refused};
      while (line.size() < t.header.size()) line.push_back("-");
      t.rows.push_back(line);
      continue;
    }
    auto line = [&](const BudgetSide& s, const std::string& predicted, const PilotFigures& pilot, const std::string& verdict) {
      std::vector<std::string> l{s.structure, mb(r.budget), mb(s.bytes_ls), predicted, fixed(s.mrays_per_s, 2),
                                 fixed(s.speedup, 2)};
      for (double e : s.rmse) l.push_back(rmse_text(e));
      for (const BiasEstimate& b : s.bias) l.push_back(bias_text(b));
      l.insert(l.end(), {fixed(pilot.error, 5), fixed(pilot.saved_work, 2), fixed(s.build_seconds, 2), verdict});
      t.rows.push_back(l);
    };
    // The plan's pilot figures for the uniform are those of its reference: the same structure here.
    const bool same = r.plan.reference == r.uniform_name;
    line(r.uniform, "-", same ? r.plan.uniform : PilotFigures{}, "");
    line(r.planned, mb(r.plan.predicted_bytes), r.plan.plan, r.lower_rmse() ? "yes" : "no");
  }
  return t;
}

Table BudgetStudy::choices() const {
  Table t;
  t.header = {"budget of", "mesh", "name", "triangles", "instances", "pilot hits", "uniform D:N", "chosen D:N", "MB",
              "pilot error", "saved work", "why"};
  for (const BudgetComparison& r : rows)
    for (const LsPlanRow& o : r.plan.rows)
      t.rows.push_back({r.uniform_name, std::to_string(o.mesh), o.name, std::to_string(o.triangles), std::to_string(o.instances),
                        std::to_string(o.hits), dn(o.reference), dn(o.chosen), mb(o.bytes), fixed(o.error, 5),
                        fixed(o.saved_work, 2), o.reason});
  return t;
}

nlohmann::json BudgetStudy::json() const {
  nlohmann::json list = nlohmann::json::array();
  for (const BudgetComparison& r : rows) {
    nlohmann::json j{{"uniform_structure", r.uniform_name}};
    if (!r.refused.empty()) {
      j["refused"] = r.refused;
    } else {
      j["budget_bytes"] = r.budget;
      j["uniform"] = side_json(r.uniform);
      j["auto"] = side_json(r.planned);
      j["auto"]["predicted_bytes"] = r.plan.predicted_bytes;
      j["auto"]["plan"] = ls_plan_json(r.plan);
      j["lower_rmse_at_every_start_bounce"] = r.lower_rmse();  // on rmse_bias
    }
    list.push_back(j);
  }
  nlohmann::json j = study_json(scene, device, settings, reference_mrays_per_s, reference_bytes);
  j["rows"] = list;
  return j;
}

void write_budget_study(const std::string& dir, const BudgetStudy& study) {
  std::filesystem::create_directories(dir);
  write_text_file(dir + "/budget.md", study.table().markdown() + "\n" + study.choices().markdown());
  write_text_file(dir + "/budget.csv", study.table().csv());
  write_text_file(dir + "/budget.json", study.json().dump(2) + "\n");
}

}  // namespace ls
