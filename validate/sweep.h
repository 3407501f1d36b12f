// `linespace-validate sweep`: the speed/accuracy/memory trade-off of F-LS and 2L-LS over integration
// depth D, subdivision N, the refusal angle, the behind-the-origin mode and the smallest subtree that
// gets a Line Space, on one scene.  Each configuration traces bounces >=
// start with its Line Space (exact before), against the all-exact reference of the same run.  The
// data is written first (CSV, JSON); the plot is a separate step (plot_tradeoff.py).
#pragma once

#include "common/base/without_repeats.h"
#include "common/structure/accel.h"
#include "validate/measure.h"
#include "validate/rmse_study.h"
#include "validate/table.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace ls {

struct SweepGrid {
  std::vector<StructureKind> families = {StructureKind::FlatLs, StructureKind::TwoLevelLs};
  std::vector<int> depths = {0, 2, 4, 6, 8};
  std::vector<int> subdivisions = {4, 6, 8};
  std::vector<float> angles = {LsLookup{}.angle_degrees};
  std::vector<LsBehind> behinds = {LsLookup{}.behind};
  std::vector<uint32_t> min_triangles = {LsBuildOptions{}.min_triangles};  // --ls-min-triangles: each value a build
  int start_bounce = 1;
};

// The figures of MeasuredFigures (exact_mrays_per_s: the exact F-BVH rendered beside this point, the
// speed-up the median of the timing rounds' ratios) and of the structure as built.
struct SweepPoint : MeasuredFigures, BuiltFigures {
  std::string structure;
  int depth = 0, subdivision = 0;
  float angle = 0.0f;
  LsBehind behind = LsBehind::Exact;
  uint32_t min_triangles = 0;
  bool pareto = false;       // no other point (nor the exact F-BVH) is at least as fast and as accurate (rmse_bias), and better in one
  std::string refused;       // non-empty: not built (the reason)
};

struct Sweep {
  std::string scene, device;
  ImageSettings settings;
  int start_bounce = 1;
  double reference_mrays_per_s = 0.0;
  size_t reference_bytes = 0;
  std::vector<SweepPoint> points;

  Table table() const;
  nlohmann::json json() const;
};

// The list flags below keep an item's first place and drop its repeats (without_repeats: "--depths
// 2,2" rendered the same configuration twice), as --thresholds does.
std::vector<int> parse_int_list(const std::string& text, const std::string& flag, int lo, int hi);
std::vector<float> parse_angle_list(const std::string& text);
std::vector<LsBehind> parse_behind_list(const std::string& text);
std::vector<uint32_t> parse_min_triangles_list(const std::string& text);
std::vector<StructureKind> parse_families(const std::string& text);

Sweep run_sweep(StudyRenderer& renderer, const std::string& scene, const SweepGrid& grid, const ImageSettings& settings, const Log& log);
// On rmse_bias (sampling noise would move the front with spp; a point without an estimate, 1 spp,
// falls back to its RMSE) and the speed-up over the exact F-BVH timed beside each point (Measured).
// The exact F-BVH (error 0, speed-up 1) takes part: a point it dominates is off the front.
void mark_pareto(std::vector<SweepPoint>& points);

// sweep.csv, sweep.json, sweep.md into dir.
void write_sweep(const std::string& dir, const Sweep& sweep);

}  // namespace ls
