// A storage buffer in host-visible, coherent memory (device-local as well where the device offers
// both, as integrated GPUs and lavapipe do).  Host-visible keeps the port short: uploads and read-backs
// are memcpy.  A buffer is never smaller than 16 bytes, so an empty array (top_nodes of a flat
// structure) still binds.
#pragma once

#include "gpu/vk_context.h"

#include <cstddef>
#include <cstring>
#include <vector>

namespace ls::gpu {

class Buffer {
 public:
  Buffer() = default;
  // `name` says in the error which array did not fit (e.g. "ls_candidates").
  Buffer(const VulkanContext& context, size_t bytes, const char* name = "buffer");
  ~Buffer();
  Buffer(Buffer&& other) noexcept;
  Buffer& operator=(Buffer&& other) noexcept;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  VkBuffer handle() const { return buffer_; }
  size_t size() const { return size_; }
  void* data() const { return mapped_; }

  void upload(const void* src, size_t bytes, size_t offset = 0) { std::memcpy(static_cast<char*>(mapped_) + offset, src, bytes); }
  void download(void* dst, size_t bytes, size_t offset = 0) const { std::memcpy(dst, static_cast<const char*>(mapped_) + offset, bytes); }

 private:
  void release();
  VkDevice device_ = VK_NULL_HANDLE;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  size_t size_ = 0;
  void* mapped_ = nullptr;
};

// A buffer holding a copy of `values`.
template <class T>
Buffer make_buffer(const VulkanContext& context, const std::vector<T>& values, const char* name = "buffer") {
  Buffer b(context, values.size() * sizeof(T), name);
  if (!values.empty()) b.upload(values.data(), values.size() * sizeof(T));
  return b;
}

}  // namespace ls::gpu
