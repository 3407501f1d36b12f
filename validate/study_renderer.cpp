#include "validate/study_renderer.h"

#include "common/base/progress.h"
#include "common/base/system_info.h"
#include "common/render/backend.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "cpu/app/cpu_backend.h"
#include "gpu/gpu_backend.h"

#include <set>
#include <utility>

namespace ls {

BuiltFigures built_figures(const Accel& accel) {
  return {accel.bytes_total(), accel.bytes_ls(), accel.ls_info.ls_nodes, accel.build_seconds};
}

StudyRenderer::StudyRenderer(std::unique_ptr<Backend> backend, const Scene& scene, const AccelOptions& options)
    : backend_(std::move(backend)), scene_(scene), options_(options) {}

std::string StudyRenderer::device() const {
  const std::string device = backend_->device();
  return device.empty() ? "cpu: " + cpu_model() : "gpu: " + device;
}

const Accel& StudyRenderer::structure(const StructureSpec& spec) {
  auto it = built_.find(spec.name());
  if (it == built_.end()) it = built_.emplace(spec.name(), backend_->build(scene_, spec, options_)).first;
  return it->second;
}

RenderResult StudyRenderer::render(const RenderOptions& options) {
  for (const StructureSpec& spec : render_structures(options)) structure(spec);  // the switch's too
  // On a terminal, each render's samples; erased when done (the study's log says what finished).
  const ProgressLine line("render", "samples", stderr_is_terminal(), ProgressEnd::Erase);
  Progress progress;
  if (line.enabled()) progress = [line](int done, int total) { line.update(size_t(done), size_t(total)); };
  return backend_->render(scene_, built_, options, progress);
}

void StudyRenderer::set_plan(const LsPlanOptions& plan) {
  options_.plan = plan;
  for (auto it = built_.begin(); it != built_.end();)
    it = it->second.spec.budgeted ? built_.erase(it) : std::next(it);
}

void StudyRenderer::set_ls_min_triangles(uint32_t min_triangles) {
  if (options_.ls.min_triangles == min_triangles) return;
  options_.ls.min_triangles = min_triangles;
  for (auto it = built_.begin(); it != built_.end();)
    it = it->second.spec.line_space() ? built_.erase(it) : std::next(it);
}

std::unique_ptr<StudyRenderer> make_cpu_study_renderer(const Scene& scene, const AccelOptions& options) {
  return std::make_unique<StudyRenderer>(make_cpu_backend(), scene, options);
}

std::unique_ptr<StudyRenderer> make_study_renderer(const std::string& device, const Scene& scene,
                                                   const AccelOptions& options) {
  if (device == "cpu") return make_cpu_study_renderer(scene, options);
  if (device == "gpu") return std::make_unique<StudyRenderer>(gpu::make_gpu_backend(""), scene, options);
  if (device.rfind("gpu:", 0) == 0)
    return std::make_unique<StudyRenderer>(gpu::make_gpu_backend(device.substr(4)), scene, options);
  throw InputError("--device " + device + ": expected cpu, gpu or gpu:NAME|INDEX");
}

size_t schedule_bytes(StudyRenderer& renderer, const Schedule& schedule, int bounces) {
  std::set<std::string> seen;
  size_t bytes = 0;
  for (int k = 0; k <= bounces; ++k) {
    const StructureSpec& spec = schedule.at(k);
    if (seen.insert(spec.name()).second) bytes += renderer.structure(spec).bytes_total();
  }
  return bytes;
}

Schedule schedule_from(const StructureSpec& spec, int start) {
  Schedule s;
  s.per_bounce.assign(size_t(start), StructureSpec{});
  s.per_bounce.push_back(spec);
  return s;
}

}  // namespace ls
