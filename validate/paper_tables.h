// `linespace-validate paper`: the paper's configurations over a list of scenes — Table 2's builds,
// Table 3's structures with the LS from bounce 1..3, Table 4's per-bounce schedules — printed beside
// the paper's figures (paper_figures.h) as ratios where absolute numbers are not comparable, followed
// by which of the paper's claims hold on our scenes.  Claims about accuracy are decided on rmse_bias
// (measure.h): a difference within two standard errors decides nothing and is reported as such.
#pragma once

#include "common/structure/accel.h"
#include "validate/measure.h"
#include "validate/rmse_study.h"

#include <set>
#include <string>
#include <vector>

namespace ls {

struct PaperOptions {
  std::vector<std::string> scenes;
  std::set<int> tables = {2, 3, 4};
  std::set<int> subdivisions = {6, 10};  // which of the paper's N to run
  ImageSettings settings;
  std::string device = "cpu";
  float heatmap_max = 0.1f;
};

// The figures of MeasuredFigures (the speed-up over the exact F-BVH timed beside it).
struct ScheduleMeasure : MeasuredFigures {
  std::string paper_name, schedule;
  size_t bytes = 0;  // the schedule's distinct structures (Measured::bytes)
  std::string refused;
};

struct PaperScene {
  std::string scene;
  size_t triangles = 0, objects = 0, instances = 0;
  int paper_scene = 0;     // index into paper::kScenes it is compared with
  RmseStudy study;         // Table 2 and 3 (rows of 2l-bvh and the twelve Line Spaces)
  std::vector<ScheduleMeasure> table4;
};

struct PaperReport {
  std::vector<PaperScene> scenes;
  std::string markdown;
  nlohmann::json json;
};

// Throws InputError for bad options (bounces < 3 with Table 3 or 4, unknown table).
PaperReport run_paper(const PaperOptions& options, const AccelOptions& accel_options, const std::string& out_dir,
                      const Log& log);

}  // namespace ls
