// The command line both programs share (docs/design.md §9): linespace-cpu and linespace-gpu declare their
// subcommands and flags here, once, and differ only in their Backend, which says where structures are
// built, rays traced and images rendered.  Exit status: 0 success, 1 a check failed, 2 bad input or
// usage (a one-line reason on stderr), 128 + signal when interrupted.
#pragma once

#include "common/render/backend.h"

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ls {

struct ProgramInfo {
  std::string name;            // "linespace-cpu"
  std::string description;     // the --help banner
  bool device_flag = false;    // --device NAME|INDEX on every subcommand (the GPU program)
  std::vector<std::string> embree_isas;  // bench --embree-isa: Embree's instruction sets, where the program runs Embree
  bool fast_path_flags = true;  // --traversal, --wide-width, --exact-width: the CPU's fast path (not the GPU program)
  // Makes the backend once the command line is parsed, for the subcommands that need one.
  std::function<std::unique_ptr<Backend>(const std::string& device)> make_backend;
  // `devices [--json]`: lists the devices the program can run on, with their drivers (the GPU program).
  std::function<void(bool json)> print_devices;
};

int run_program(int argc, char** argv, const ProgramInfo& info);

}  // namespace ls
