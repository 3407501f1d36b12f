// Where structures are built, rays traced and images rendered: the one interface of the two back
// ends (CpuBackend, cpu/app/cpu_backend.h; GpuBackend, gpu/gpu_backend.h).  The command line both
// programs share (cpu/app/cli_program.h) and the validator's studies (validate/study_renderer.h) drive
// them through it.
#pragma once

#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"

#include <map>
#include <string>
#include <vector>

namespace ls {

class Backend {
 public:
  virtual ~Backend() = default;
  // Who traces: "" for this CPU (reports then say "cpu: MODEL"), else the device's description.
  virtual std::string device() const = 0;
  virtual Accel build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) = 0;
  // `build`: builds and prints the structure (docs/design.md §9 keys), with what this backend adds.
  virtual void print_build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options, bool json) = 0;
  // `trace`: hits and Line Space counters (added to *counters); `timing` says how long, for the log line.
  virtual std::vector<lsk::Hit> trace(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays,
                                      bool any_hit, lsk::LsCounters* counters, std::string* timing) = 0;
  virtual RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures,
                              const RenderOptions& options, const Progress& progress) = 0;
  // `bench`: times and prints (text or JSON); embree_isa: Embree's instruction set where the backend
  // runs Embree beside its structures (embree_tracer.h).
  virtual void bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& specs,
                     int repeats, const AccelOptions& options, const LsLookup& lookup, bool any_hit,
                     const std::string& embree_isa, bool json) = 0;
  // `render --frames` (render_frames.h): brings a two-level structure made by build() to a posed scene
  // by its top level alone (top_level_update.h).  A backend with a device copy of the structure
  // refreshes that copy's top level here, and nothing else of it.
  virtual TopLevelUpdate update_top_level(const Scene& posed, Accel& accel, TopLevelMode mode) = 0;
};

}  // namespace ls
