// A structure's std430 arrays (ls::Accel, common/structure/accel.h) uploaded unchanged to the GPU, in the binding
// order of shaders/scene_buffers.glsl.
#pragma once

#include "common/structure/accel.h"
#include "gpu/vk_buffer.h"

#include <vector>

namespace ls::gpu {

class GpuAccel {
 public:
  GpuAccel(const VulkanContext& context, const Accel& accel);

  // Bindings 0..9 of scene_buffers.glsl.
  std::vector<const Buffer*> bindings() const;
  // Copies accel.ls_candidates again (after a search filled them).
  void upload_candidates(const Accel& accel);
  // Copies the top level again (top_nodes, instances) after update_top_level (render --frames): the
  // object nodes, triangles and Line Space on the device are not touched.
  void upload_top_level(const Accel& accel);
  // The parameters of lsk::TraceContext for this structure (ls_enabled, ls_cos2, two_level).
  // The push constants of a trace with `lookup` (structure and Line Space parameters).
  lsk::ShaderParams params(const LsLookup& lookup) const;

 private:
  const VulkanContext* context_;
  Buffer nodes_, tris_, tri_ids_, tri_instances_, top_nodes_, instances_, node_ls_, ls_nodes_, ls_candidates_, ls_records_;
  lsk::ShaderParams params_{};
};

}  // namespace ls::gpu
