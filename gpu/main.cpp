// linespace-gpu: the Vulkan port's command line, with linespace-cpu's subcommands and flags (docs/design.md §9;
// cpu/app/cli_program.h) plus --device NAME|INDEX.  Line Space candidates are searched, rays traced and
// paths shaded on the device; every figure is printed with the device's name.
#include "cpu/app/cli_program.h"
#include "gpu/device_list.h"
#include "gpu/gpu_backend.h"

int main(int argc, char** argv) {
  ls::ProgramInfo info;
  info.name = "linespace-gpu";
  info.description = "linespace-gpu: exact and Line Space ray tracing on a Vulkan device";
  info.device_flag = true;
  info.fast_path_flags = false;  // the device traces with the shared kernels
  info.make_backend = [](const std::string& device) { return ls::gpu::make_gpu_backend(device); };
  info.print_devices = ls::gpu::print_devices;
  return ls::run_program(argc, argv, info);
}
