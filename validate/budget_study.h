// `linespace-validate budget`: the per-object choice of 2l-ls:auto (cpu/build/ls_budget.h) against uniform
// parameters of the same memory.  For each uniform 2l-ls:D:N: its bytes_ls become the
// budget of a 2l-ls:auto, and both are rendered from each start bounce against the all-exact reference
// with the same random numbers (the measurement `rmse` makes): RMSE and rmse_bias per start bounce, indirect MRays/s,
// memory (the plan's predicted bytes beside the built structure's), and the pilot's figures.
#pragma once

#include "common/structure/accel.h"
#include "cpu/build/ls_budget.h"
#include "validate/measure.h"
#include "validate/rmse_study.h"
#include "validate/table.h"

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ls {

struct BudgetSide {
  std::string structure;
  std::vector<double> rmse;  // from bounce 1..B
  std::vector<BiasEstimate> bias;  // from bounce 1..B: rmse_bias, its standard error, the noise floor
  std::vector<int> spp;            // from bounce 1..B
  std::vector<std::string> spp_stop;
  double mrays_per_s = 0.0;  // with the structure from bounce 1
  double speedup = 0.0;      // the same over the exact F-BVH timed beside it (Measured)
  size_t bytes_ls = 0;
  double build_seconds = 0.0;
};

struct BudgetComparison {
  std::string uniform_name;
  size_t budget = 0;         // the uniform's bytes_ls
  BudgetSide uniform, planned;
  LsPlan plan;               // of the 2l-ls:auto
  std::string refused;       // non-empty: the uniform structure was refused (memory), no figures
  bool lower_rmse() const;   // lower rmse_bias at every start bounce (RMSE without an estimate, 1 spp)
};

struct BudgetStudy {
  std::string scene, device;
  ImageSettings settings;
  double reference_mrays_per_s = 0.0;
  size_t reference_bytes = 0;
  std::vector<BudgetComparison> rows;

  Table table() const;       // one line per structure
  Table choices() const;     // the plans, object by object, beside the uniform's D and N
  nlohmann::json json() const;
};

BudgetStudy run_budget_study(StudyRenderer& renderer, const std::string& scene, const std::vector<StructureSpec>& uniform,
                             const ImageSettings& settings, const LsPlanOptions& plan, const Log& log);

// budget.md (both tables), budget.csv (the first), budget.json into dir.
void write_budget_study(const std::string& dir, const BudgetStudy& study);

}  // namespace ls
