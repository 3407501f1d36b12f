// The command line both programs share (DESIGN §9): linespace-cpu and linespace-gpu declare their
// subcommands and flags here, once, and differ only in their Backend, which says where structures are
// built, rays traced and images rendered.  Exit status: 0 success, 1 a check failed, 2 bad input or
// usage (a one-line reason on stderr), 128 + signal when interrupted.
#pragma once

#include "accel.h"
#include "path_tracer.h"
#include "top_level_update.h"

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ls {

class Backend {
 public:
  virtual ~Backend() = default;
  // Who traces: "" for this CPU (reports then say "cpu: MODEL"), else the device's description.
  virtual std::string device() const = 0;
  virtual Accel build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) = 0;
  // `build`: builds and prints the structure (DESIGN §9 keys), with what this backend adds.
  virtual void print_build(const Scene& scene, const StructureSpec& spec, const AccelOptions& options, bool json) = 0;
  // `trace`: hits and Line Space counters (added to *counters); `timing` says how long, for the log line.
  virtual std::vector<lsk::Hit> trace(const Accel& accel, const std::vector<lsk::Ray>& rays, bool any_hit,
                                      lsk::LsCounters* counters, std::string* timing) = 0;
  virtual RenderResult render(const Scene& scene, const std::map<std::string, Accel>& structures,
                              const RenderOptions& options, const Progress& progress) = 0;
  // `bench`: times and prints (text or JSON); embree_isa: Embree's instruction set where the backend
  // runs Embree beside its structures (embree_tracer.h).
  virtual void bench(const Scene& scene, const std::vector<lsk::Ray>& rays, const std::vector<StructureSpec>& specs,
                     int repeats, const AccelOptions& options, bool any_hit, const std::string& embree_isa, bool json) = 0;
  // `render --frames` (render_frames.h): brings a two-level structure made by build() to a posed scene
  // by its top level alone (top_level_update.h).  A backend with a device copy of the structure
  // refreshes that copy's top level here, and nothing else of it.
  virtual TopLevelUpdate update_top_level(const Scene& posed, Accel& accel, TopLevelMode mode) {
    return ls::update_top_level(posed, accel, mode);
  }
};

struct ProgramInfo {
  std::string name;            // "linespace-cpu"
  std::string description;     // the --help banner
  bool device_flag = false;    // --device NAME|INDEX on every subcommand (the GPU program)
  bool fast_path_flags = true;  // --traversal, --wide-width, --exact-width: the CPU's fast path (not the GPU program)
  // Makes the backend once the command line is parsed, for the subcommands that need one.
  std::function<std::unique_ptr<Backend>(const std::string& device)> make_backend;
};

int run_program(int argc, char** argv, const ProgramInfo& info);

}  // namespace ls
