// What every study of the validator needs from a back end: the structures it builds (and their
// memory), and renders with a per-bounce schedule.  Structures are built once and reused by every
// render that names them, so a table of many schedules costs one build per structure.
#pragma once

#include "accel.h"
#include "path_tracer.h"
#include "scene.h"
#include "structure_name.h"

#include <map>
#include <memory>
#include <string>

namespace ls {

class StudyRenderer {
 public:
  virtual ~StudyRenderer() = default;
  virtual std::string device() const = 0;
  // Builds the structure unless it is built already; throws InputError when refused (memory budget).
  virtual const Accel& structure(const StructureSpec& spec) = 0;
  // Renders; every structure of the schedule is built first if needed.
  virtual RenderResult render(const RenderOptions& options) = 0;
  // Frees a structure no later render needs (sweeps over many Line Spaces).
  virtual void release(const StructureSpec& spec) = 0;
  // New Line Space options (a sweep over the refusal angle): built Line Spaces are dropped.
  virtual void set_ls_options(const LsOptions& options) = 0;
};

// The CPU reference renderer (cpu/path_tracer).
class CpuStudyRenderer : public StudyRenderer {
 public:
  CpuStudyRenderer(const Scene& scene, const AccelOptions& options) : scene_(scene), options_(options) {}
  std::string device() const override;
  const Accel& structure(const StructureSpec& spec) override;
  RenderResult render(const RenderOptions& options) override;
  void release(const StructureSpec& spec) override { built_.erase(spec.name()); }
  void set_ls_options(const LsOptions& options) override;

 private:
  const Scene& scene_;
  AccelOptions options_;
  std::map<std::string, Accel> built_;
};

// "cpu", "gpu" (the preferred Vulkan device) or "gpu:NAME|INDEX"; throws InputError for anything else
// or when there is no such Vulkan device.
std::unique_ptr<StudyRenderer> make_study_renderer(const std::string& device, const Scene& scene,
                                                   const AccelOptions& options);

// Bytes of the distinct structures of a schedule (what a renderer holds while it runs).
size_t schedule_bytes(StudyRenderer& renderer, const Schedule& schedule, int bounces);

// The schedule that traces bounces < start with the exact F-BVH and bounces >= start with `spec`.
Schedule schedule_from(const StructureSpec& spec, int start);

}  // namespace ls
