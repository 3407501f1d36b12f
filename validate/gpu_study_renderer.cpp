#include "gpu_study_renderer.h"

#include "gpu_line_space.h"
#include "gpu_renderer.h"

namespace ls {

GpuStudyRenderer::GpuStudyRenderer(const Scene& scene, const AccelOptions& options, const std::string& device_choice)
    : context_(std::make_unique<gpu::VulkanContext>(device_choice)), scene_(scene), options_(options) {}

std::string GpuStudyRenderer::device() const { return "gpu: " + context_->description(); }

const Accel& GpuStudyRenderer::structure(const StructureSpec& spec) {
  auto it = built_.find(spec.name());
  if (it == built_.end()) it = built_.emplace(spec.name(), gpu::build_accel_gpu(*context_, scene_, spec, options_)).first;
  return it->second;
}

RenderResult GpuStudyRenderer::render(const RenderOptions& options) {
  for (const StructureSpec& spec : render_structures(options)) structure(spec);  // the switch's too
  return gpu::render_gpu(*context_, scene_, built_, options);
}

void GpuStudyRenderer::set_ls_options(const LsOptions& options) {
  options_.ls = options;
  for (auto it = built_.begin(); it != built_.end();)
    it = it->second.spec.line_space() ? built_.erase(it) : std::next(it);
}

}  // namespace ls
