// The studies' GPU back end (`--device gpu` or `gpu:NAME|INDEX`): structures with Line Space
// candidates searched on the GPU, renders whose rays are traced on the GPU (gpu/gpu_renderer.h).
#pragma once

#include "study_renderer.h"
#include "vk_context.h"

#include <memory>

namespace ls {

class GpuStudyRenderer : public StudyRenderer {
 public:
  GpuStudyRenderer(const Scene& scene, const AccelOptions& options, const std::string& device_choice);
  std::string device() const override;
  const Accel& structure(const StructureSpec& spec) override;
  RenderResult render(const RenderOptions& options) override;
  void release(const StructureSpec& spec) override { built_.erase(spec.name()); }
  void set_ls_options(const LsOptions& options) override;

 private:
  std::unique_ptr<gpu::VulkanContext> context_;
  const Scene& scene_;
  AccelOptions options_;
  std::map<std::string, Accel> built_;
};

}  // namespace ls
