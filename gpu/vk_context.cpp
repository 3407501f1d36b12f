#include "gpu/vk_context.h"

#include "common/model/scene.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace ls::gpu {
namespace {

std::string type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

// Lower is preferred: discrete GPUs first, CPU drivers (lavapipe) last.
int preference(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

DeviceInfo basic_info(uint32_t index, const VkPhysicalDeviceProperties& p) {
  DeviceInfo d;
  d.index = index;
  d.name = p.deviceName;
  d.type = type_name(p.deviceType);
  return d;
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

VkInstance create_instance() {
  VkApplicationInfo app{};
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.pApplicationName = "linespace";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ci{};
  ci.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  ci.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = vkCreateInstance(&ci, nullptr, &instance);
  if (r != VK_SUCCESS)
    throw InputError("no Vulkan: vkCreateInstance failed (" + std::to_string(int(r)) +
                     "); install a Vulkan driver (mesa-vulkan-drivers gives the lavapipe CPU device)");
  return instance;
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance instance) {
  uint32_t count = 0;
  vkEnumeratePhysicalDevices(instance, &count, nullptr);
  std::vector<VkPhysicalDevice> devices(count);
  if (count) vkEnumeratePhysicalDevices(instance, &count, devices.data());
  devices.resize(count);
  return devices;
}

// The first queue family with compute, or UINT32_MAX.
uint32_t compute_family(VkPhysicalDevice d, uint32_t& timestamp_bits) {
  uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(d, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(d, &count, families.data());
  for (uint32_t i = 0; i < count; ++i)
    if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) {
      timestamp_bits = families[i].timestampValidBits;
      return i;
    }
  return UINT32_MAX;
}

std::string device_list(const std::vector<DeviceInfo>& all) {
  std::string s;
  for (const DeviceInfo& d : all) s += (s.empty() ? "" : ", ") + std::to_string(d.index) + ": " + d.name;
  return s.empty() ? "none" : s;
}

}  // namespace

void check_vk(VkResult result, const char* what) {
  if (result != VK_SUCCESS) throw std::runtime_error(std::string("Vulkan: ") + what + " failed (" + std::to_string(int(result)) + ")");
}

std::vector<DeviceInfo> VulkanContext::list_devices() {
  VkInstance instance = create_instance();
  std::vector<DeviceInfo> out;
  int preferred = -1;
  VkPhysicalDeviceType preferred_type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  for (VkPhysicalDevice d : physical_devices(instance)) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(d, &p);
    DeviceInfo info = basic_info(uint32_t(out.size()), p);
    info.api_version = std::to_string(VK_API_VERSION_MAJOR(p.apiVersion)) + "." + std::to_string(VK_API_VERSION_MINOR(p.apiVersion)) +
                       "." + std::to_string(VK_API_VERSION_PATCH(p.apiVersion));
    info.vendor_id = p.vendorID;
    info.device_id = p.deviceID;
    info.max_storage_buffer_range = p.limits.maxStorageBufferRange;
    if (p.apiVersion >= VK_API_VERSION_1_2) {  // driver properties are core from 1.2 on
      VkPhysicalDeviceDriverProperties driver{};
      driver.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES;
      VkPhysicalDeviceProperties2 p2{};
      p2.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2;
      p2.pNext = &driver;
      vkGetPhysicalDeviceProperties2(d, &p2);
      info.driver_name = driver.driverName;
      info.driver_info = driver.driverInfo;
    }
    uint32_t bits = 0;
    info.compute = compute_family(d, bits) != UINT32_MAX;
    // The same rule as the constructor's choice without --device.
    if (info.compute && (preferred < 0 || preference(p.deviceType) < preference(preferred_type))) {
      preferred = int(out.size());
      preferred_type = p.deviceType;
    }
    out.push_back(info);
  }
  if (preferred >= 0) out[size_t(preferred)].preferred = true;
  vkDestroyInstance(instance, nullptr);
  return out;
}

VulkanContext::VulkanContext(const std::string& device_choice) {
  instance_ = create_instance();
  try {
    const std::vector<VkPhysicalDevice> devices = physical_devices(instance_);
    std::vector<DeviceInfo> all;
    std::vector<VkPhysicalDeviceProperties> props(devices.size());
    for (uint32_t i = 0; i < devices.size(); ++i) {
      vkGetPhysicalDeviceProperties(devices[i], &props[i]);
      all.push_back(basic_info(i, props[i]));
    }
    int chosen = -1;
    if (!device_choice.empty()) {
      const bool numeric = std::all_of(device_choice.begin(), device_choice.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
      for (uint32_t i = 0; i < devices.size() && chosen < 0; ++i)
        if (numeric ? std::to_string(i) == device_choice : lower(all[i].name).find(lower(device_choice)) != std::string::npos)
          chosen = int(i);
      if (chosen < 0) throw InputError("--device '" + device_choice + "' matches no Vulkan device (devices: " + device_list(all) + ")");
    } else {
      for (uint32_t i = 0; i < devices.size(); ++i) {
        uint32_t bits = 0;
        if (compute_family(devices[i], bits) == UINT32_MAX) continue;
        if (chosen < 0 || preference(props[i].deviceType) < preference(props[size_t(chosen)].deviceType)) chosen = int(i);
      }
      if (chosen < 0) throw InputError("no Vulkan device with a compute queue (devices: " + device_list(all) + ")");
    }
    physical_ = devices[size_t(chosen)];
    properties_ = props[size_t(chosen)];
    info_ = all[size_t(chosen)];
    vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
    queue_family_ = compute_family(physical_, timestamp_valid_bits_);
    if (queue_family_ == UINT32_MAX) throw InputError("Vulkan device '" + info_.name + "' has no compute queue");

    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qci{};
    qci.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
    qci.queueFamilyIndex = queue_family_;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    VkDeviceCreateInfo dci{};
    dci.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    check_vk(vkCreateDevice(physical_, &dci, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
    VkCommandPoolCreateInfo pci{};
    pci.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = queue_family_;
    check_vk(vkCreateCommandPool(device_, &pci, nullptr, &pool_), "vkCreateCommandPool");
    VkFenceCreateInfo fci{};
    fci.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
    check_vk(vkCreateFence(device_, &fci, nullptr, &fence_), "vkCreateFence");
  } catch (...) {
    release();
    throw;
  }
}

VulkanContext::~VulkanContext() { release(); }

void VulkanContext::release() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    if (fence_) vkDestroyFence(device_, fence_, nullptr);
    if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
  fence_ = VK_NULL_HANDLE;
  pool_ = VK_NULL_HANDLE;
  device_ = VK_NULL_HANDLE;
  instance_ = VK_NULL_HANDLE;
}

std::string VulkanContext::description() const {
  return info_.name + " (" + info_.type + ", Vulkan " + std::to_string(VK_API_VERSION_MAJOR(properties_.apiVersion)) + "." +
         std::to_string(VK_API_VERSION_MINOR(properties_.apiVersion)) + ")";
}

uint32_t VulkanContext::memory_type(uint32_t type_bits, VkMemoryPropertyFlags wanted) const {
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i)
    if ((type_bits & (1u << i)) && (memory_.memoryTypes[i].propertyFlags & wanted) == wanted) return i;
  return UINT32_MAX;
}

VkCommandBuffer VulkanContext::begin() const {
  VkCommandBufferAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  ai.commandPool = pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  check_vk(vkAllocateCommandBuffers(device_, &ai, &cmd), "vkAllocateCommandBuffers");
  VkCommandBufferBeginInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check_vk(vkBeginCommandBuffer(cmd, &bi), "vkBeginCommandBuffer");
  return cmd;
}

void VulkanContext::end_and_wait(VkCommandBuffer cmd) const {
  check_vk(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
  VkSubmitInfo si{};
  si.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  check_vk(vkQueueSubmit(queue_, 1, &si, fence_), "vkQueueSubmit");
  const VkResult r = vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX);
  vkResetFences(device_, 1, &fence_);
  vkFreeCommandBuffers(device_, pool_, 1, &cmd);
  check_vk(r, "vkWaitForFences");
}

}  // namespace ls::gpu
