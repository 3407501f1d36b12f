#include "gpu/vk_buffer.h"

#include "common/model/scene.h"

#include <algorithm>
#include <string>
#include <utility>

namespace ls::gpu {

Buffer::Buffer(const VulkanContext& context, size_t bytes, const char* name)
    : device_(context.device()), size_(std::max<size_t>(bytes, 16)) {
  // Each array is bound whole, so it must fit one storage-buffer range (gpu/README.md, "Limits").
  if (size_ > context.limits().maxStorageBufferRange) {
    const std::string what(name);
    const std::string hint = what == "ls_candidates" || what == "ls_nodes" ? "lower N or D"
                             : what == "rays" || what == "hits"           ? "trace fewer rays at once"
                                                                           : "use a two-level structure or a smaller scene";
    throw InputError("the GPU array '" + what + "' takes " + std::to_string(size_ >> 20) + " MiB, over the maxStorageBufferRange (" +
                     std::to_string(context.limits().maxStorageBufferRange >> 20) + " MiB) of " + context.info().name + ": " + hint);
  }
  VkBufferCreateInfo bci{};
  bci.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bci.size = size_;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  check_vk(vkCreateBuffer(device_, &bci, nullptr, &buffer_), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device_, buffer_, &req);
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  uint32_t type = context.memory_type(req.memoryTypeBits, host | VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (type == UINT32_MAX) type = context.memory_type(req.memoryTypeBits, host);
  if (type == UINT32_MAX) {
    release();
    throw std::runtime_error("Vulkan: no host-visible coherent memory type for storage buffers");
  }
  VkMemoryAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = type;
  const VkResult r = vkAllocateMemory(device_, &ai, nullptr, &memory_);
  if (r != VK_SUCCESS) {
    release();
    throw InputError("the GPU could not allocate " + std::to_string(req.size >> 20) + " MiB (" + std::to_string(int(r)) + ")");
  }
  check_vk(vkBindBufferMemory(device_, buffer_, memory_, 0), "vkBindBufferMemory");
  check_vk(vkMapMemory(device_, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
}

Buffer::~Buffer() { release(); }

void Buffer::release() {
  if (memory_) {
    if (mapped_) vkUnmapMemory(device_, memory_);
    vkFreeMemory(device_, memory_, nullptr);
  }
  if (buffer_) vkDestroyBuffer(device_, buffer_, nullptr);
  memory_ = VK_NULL_HANDLE;
  buffer_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
}

Buffer::Buffer(Buffer&& other) noexcept { *this = std::move(other); }

Buffer& Buffer::operator=(Buffer&& other) noexcept {
  if (this != &other) {
    release();
    device_ = std::exchange(other.device_, VK_NULL_HANDLE);
    buffer_ = std::exchange(other.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
    size_ = std::exchange(other.size_, 0);
    mapped_ = std::exchange(other.mapped_, nullptr);
  }
  return *this;
}

}  // namespace ls::gpu
