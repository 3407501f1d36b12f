// The Vulkan instance, the chosen compute device, its queue and a command pool (docs/design.md §4).
// Device choice: `--device NAME|INDEX` picks one (INDEX in vkEnumeratePhysicalDevices order, NAME a
// case-insensitive substring of the device name); without it a discrete GPU is preferred, then an
// integrated or virtual one, then a CPU driver such as Mesa's lavapipe.  No Vulkan loader, no device or
// no match: ls::InputError with a one-line reason (the programs exit 2).
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <string>
#include <vector>

namespace ls::gpu {

struct DeviceInfo {
  uint32_t index = 0;
  std::string name;
  std::string type;  // "discrete", "integrated", "virtual", "cpu", "other"
  // What `linespace-gpu devices` prints (empty where the device is older than Vulkan 1.2).
  std::string api_version;  // "1.3.255"
  std::string driver_name, driver_info;  // VkPhysicalDeviceDriverProperties: "NVIDIA", "550.54.15"
  uint32_t vendor_id = 0, device_id = 0;
  uint64_t max_storage_buffer_range = 0;
  bool compute = false;    // has a compute queue
  bool preferred = false;  // the one chosen without --device
};

class VulkanContext {
 public:
  explicit VulkanContext(const std::string& device_choice = "");
  ~VulkanContext();
  VulkanContext(const VulkanContext&) = delete;
  VulkanContext& operator=(const VulkanContext&) = delete;

  VkDevice device() const { return device_; }
  VkPhysicalDevice physical() const { return physical_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
  const DeviceInfo& info() const { return info_; }
  std::string description() const;  // "NAME (TYPE, Vulkan X.Y)": printed with every figure

  // Records with `record`, submits, and waits for the queue to finish.
  template <class Record>
  void submit_and_wait(Record&& record) const {
    VkCommandBuffer cmd = begin();
    record(cmd);
    end_and_wait(cmd);
  }
  bool has_timestamps() const { return timestamp_valid_bits_ > 0; }
  double timestamp_period_ns() const { return double(properties_.limits.timestampPeriod); }
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags wanted) const;

  // Every device the loader reports (for messages, --device and `devices`); InputError without Vulkan.
  static std::vector<DeviceInfo> list_devices();

 private:
  void release();
  VkCommandBuffer begin() const;
  void end_and_wait(VkCommandBuffer cmd) const;

  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  DeviceInfo info_;
  uint32_t queue_family_ = 0;
  uint32_t timestamp_valid_bits_ = 0;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
};

// Throws std::runtime_error naming `what` when a Vulkan call fails.
void check_vk(VkResult result, const char* what);

}  // namespace ls::gpu
