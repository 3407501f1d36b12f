#include "gpu/device_list.h"

#include "common/model/scene.h"
#include "gpu/vk_context.h"

#include <nlohmann/json.hpp>

#include <cstdio>

namespace ls::gpu {

void print_devices(bool json) {
  const std::vector<DeviceInfo> devices = VulkanContext::list_devices();
  if (devices.empty())
    throw InputError("the Vulkan loader found no device (no driver's ICD file, or the driver did not load; VK_LOADER_DEBUG=error tells which)");
  if (json) {
    nlohmann::json list = nlohmann::json::array();
    for (const DeviceInfo& d : devices)
      list.push_back({{"index", d.index}, {"name", d.name}, {"type", d.type}, {"api_version", d.api_version},
                      {"driver_name", d.driver_name}, {"driver_info", d.driver_info}, {"vendor_id", d.vendor_id},
                      {"device_id", d.device_id}, {"max_storage_buffer_range", d.max_storage_buffer_range},
                      {"compute", d.compute}, {"default", d.preferred}});
    std::printf("%s\n", nlohmann::json{{"devices", list}}.dump(2).c_str());
    return;
  }
  for (const DeviceInfo& d : devices)
    std::printf("%u: %s (%s, Vulkan %s), driver %s %s, vendor 0x%04x device 0x%04x, maxStorageBufferRange %llu MiB%s%s\n",
                d.index, d.name.c_str(), d.type.c_str(), d.api_version.c_str(),
                d.driver_name.empty() ? "(unnamed)" : d.driver_name.c_str(), d.driver_info.c_str(), d.vendor_id, d.device_id,
                (unsigned long long)(d.max_storage_buffer_range >> 20), d.compute ? "" : ", no compute queue",
                d.preferred ? "  [default]" : "");
}

}  // namespace ls::gpu
