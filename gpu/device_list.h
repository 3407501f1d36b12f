// `linespace-gpu devices [--json]`: every Vulkan device the loader finds, with its type, Vulkan version
// and driver, and which one the programs choose without --device.  A script on an unknown machine
// (scripts/gpu-check.sh) reads it to name the device and driver its figures come from.
#pragma once

namespace ls::gpu {

// Prints one line per device (or {"devices": [...]} with json); throws InputError (exit 2) without
// Vulkan or without any device.
void print_devices(bool json);

}  // namespace ls::gpu
