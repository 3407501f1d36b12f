// A compute pipeline over storage buffers at bindings 0..n-1 of set 0 plus one push-constant block,
// and a timestamp pair to time the kernels recorded between begin() and end().
#pragma once

#include "gpu/vk_buffer.h"

#include <cstdint>
#include <vector>

namespace ls::gpu {

class ComputePipeline {
 public:
  ComputePipeline(const VulkanContext& context, const std::vector<uint32_t>& spirv, uint32_t bindings, uint32_t push_bytes);
  ~ComputePipeline();
  ComputePipeline(const ComputePipeline&) = delete;
  ComputePipeline& operator=(const ComputePipeline&) = delete;

  // Points binding i at buffers[i].  Only between submissions (the context waits for each).
  void bind(const std::vector<const Buffer*>& buffers);
  // Records push constants and a dispatch of groups_x x groups_y work groups.
  void record(VkCommandBuffer cmd, const void* push, uint32_t groups_x, uint32_t groups_y = 1) const;

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  uint32_t bindings_ = 0;
  uint32_t push_bytes_ = 0;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
};

// Device time of the commands recorded between begin() and end() in one command buffer, from
// timestamp queries; 0 where the queue has no timestamps (callers then report wall time).
class KernelTimer {
 public:
  explicit KernelTimer(const VulkanContext& context);
  ~KernelTimer();
  KernelTimer(const KernelTimer&) = delete;
  KernelTimer& operator=(const KernelTimer&) = delete;
  void begin(VkCommandBuffer cmd) const;
  void end(VkCommandBuffer cmd) const;
  double seconds() const;  // after the submission completed

 private:
  const VulkanContext& context_;
  VkQueryPool pool_ = VK_NULL_HANDLE;
};

// Memory barrier between two dispatches (the second reads what the first wrote).
void compute_barrier(VkCommandBuffer cmd);

}  // namespace ls::gpu
