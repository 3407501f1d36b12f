// What every study of the validator needs from a back end: the structures it builds (and their
// memory), and renders with a per-bounce schedule.  One caching adaptor over a Backend
// (common/render/backend.h), the CPU's or the GPU's: structures are built once and reused by every
// render that names them, so a table of many schedules costs one build per structure.
#pragma once

#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/render/backend.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"

#include <map>
#include <memory>
#include <string>

namespace ls {

// What a built structure costs, as the study rows of rmse, sweep and paper report it.
struct BuiltFigures {
  size_t bytes = 0;     // the structure's own (Accel::bytes_total)
  size_t bytes_ls = 0;  // of it, its Line Space
  size_t ls_nodes = 0;
  double build_seconds = 0.0;
};
BuiltFigures built_figures(const Accel& accel);

class StudyRenderer {
 public:
  StudyRenderer(std::unique_ptr<Backend> backend, const Scene& scene, const AccelOptions& options);
  // "cpu: MODEL" or "gpu: DEVICE".
  std::string device() const;
  // Builds the structure unless it is built already; throws InputError when refused (memory budget).
  const Accel& structure(const StructureSpec& spec);
  // Renders; every structure of the schedule is built first if needed.
  RenderResult render(const RenderOptions& options);
  // Frees a structure no later render needs (sweeps over many Line Spaces).
  void release(const StructureSpec& spec) { built_.erase(spec.name()); }
  // New 2l-ls:auto planner options (the budget study): a built 2l-ls:auto structure is dropped.
  void set_plan(const LsPlanOptions& plan);
  // A new --ls-min-triangles: the built Line Space structures are dropped.
  void set_ls_min_triangles(uint32_t min_triangles);

 private:
  std::unique_ptr<Backend> backend_;
  const Scene& scene_;
  AccelOptions options_;
  std::map<std::string, Accel> built_;
};

// The CPU back end's study renderer.
std::unique_ptr<StudyRenderer> make_cpu_study_renderer(const Scene& scene, const AccelOptions& options);

// "cpu", "gpu" (the preferred Vulkan device) or "gpu:NAME|INDEX"; throws InputError for anything else
// or when there is no such Vulkan device.
std::unique_ptr<StudyRenderer> make_study_renderer(const std::string& device, const Scene& scene,
                                                   const AccelOptions& options);

// Bytes of the distinct structures of a schedule (what a renderer holds while it runs).
size_t schedule_bytes(StudyRenderer& renderer, const Schedule& schedule, int bounces);

// The schedule that traces bounces < start with the exact F-BVH and bounces >= start with `spec`.
Schedule schedule_from(const StructureSpec& spec, int start);

}  // namespace ls
