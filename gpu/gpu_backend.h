// The GPU back end: Line Space candidates searched, rays traced and paths shaded on a Vulkan device
// (the BVHs are built on the host, as the CPU builds them).  linespace-gpu and the validator's GPU
// studies use it through the Backend interface (common/render/backend.h).
#pragma once

#include "common/render/backend.h"

#include <memory>
#include <string>

namespace ls::gpu {

// device_choice: a device's name or index ("" for the preferred one); throws InputError when there
// is no such Vulkan device.
std::unique_ptr<Backend> make_gpu_backend(const std::string& device_choice);

}  // namespace ls::gpu
