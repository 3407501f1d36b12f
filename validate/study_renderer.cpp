#include "study_renderer.h"

#include "bench.h"
#include "gpu_study_renderer.h"

#include <set>

namespace ls {

std::string CpuStudyRenderer::device() const { return "cpu: " + cpu_model(); }

const Accel& CpuStudyRenderer::structure(const StructureSpec& spec) {
  auto it = built_.find(spec.name());
  if (it == built_.end()) it = built_.emplace(spec.name(), build_accel(scene_, spec, options_)).first;
  return it->second;
}

RenderResult CpuStudyRenderer::render(const RenderOptions& options) {
  for (const StructureSpec& spec : render_structures(options)) structure(spec);  // the switch's too
  return ls::render(scene_, built_, options);
}

void CpuStudyRenderer::set_ls_options(const LsOptions& options) {
  options_.ls = options;
  for (auto it = built_.begin(); it != built_.end();)
    it = it->second.spec.line_space() ? built_.erase(it) : std::next(it);
}

std::unique_ptr<StudyRenderer> make_study_renderer(const std::string& device, const Scene& scene,
                                                   const AccelOptions& options) {
  if (device == "cpu") return std::make_unique<CpuStudyRenderer>(scene, options);
  if (device == "gpu") return std::make_unique<GpuStudyRenderer>(scene, options, "");
  if (device.rfind("gpu:", 0) == 0) return std::make_unique<GpuStudyRenderer>(scene, options, device.substr(4));
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
