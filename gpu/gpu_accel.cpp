#include "gpu/gpu_accel.h"

#include "common/structure/accel.h"

namespace ls::gpu {

GpuAccel::GpuAccel(const VulkanContext& context, const Accel& accel)
    : context_(&context),
      nodes_(make_buffer(context, accel.nodes, "nodes")),
      tris_(make_buffer(context, accel.tris, "tris")),
      tri_ids_(make_buffer(context, accel.tri_ids, "tri_ids")),
      tri_instances_(make_buffer(context, accel.tri_instances, "tri_instances")),
      top_nodes_(make_buffer(context, accel.top_nodes, "top_nodes")),
      instances_(make_buffer(context, accel.instances, "instances")),
      node_ls_(make_buffer(context, accel.node_ls, "node_ls")),
      ls_nodes_(make_buffer(context, accel.ls_nodes, "ls_nodes")),
      ls_candidates_(make_buffer(context, accel.ls_candidates, "ls_candidates")),
      ls_records_(make_buffer(context, accel.ls_records, "ls_records")) {
  params_.ls_enabled = trace_context(accel).ls_enabled;  // the CPU's rule, so both sides agree
  params_.two_level = accel.spec.two_level() ? 1u : 0u;
}

std::vector<const Buffer*> GpuAccel::bindings() const {
  return {&nodes_, &tris_, &tri_ids_, &tri_instances_, &top_nodes_, &instances_, &node_ls_, &ls_nodes_, &ls_candidates_, &ls_records_};
}

void GpuAccel::upload_candidates(const Accel& accel) {
  if (!accel.ls_candidates.empty()) ls_candidates_.upload(accel.ls_candidates.data(), accel.ls_candidates.size() * sizeof(uint32_t));
}

void GpuAccel::upload_top_level(const Accel& accel) {
  // A rebuilt top level may hold more nodes than the buffer: then it gets a new one (bindings() hands
  // out the member's address, which stays; pipelines bind per dispatch).
  const auto refresh = [&](Buffer& buffer, const auto& values, const char* name) {
    const size_t bytes = values.size() * sizeof(values[0]);
    if (bytes > buffer.size()) buffer = make_buffer(*context_, values, name);
    else if (bytes > 0) buffer.upload(values.data(), bytes);
  };
  refresh(top_nodes_, accel.top_nodes, "top_nodes");
  refresh(instances_, accel.instances, "instances");
}

lsk::ShaderParams GpuAccel::params(const LsLookup& lookup) const {
  lsk::ShaderParams p = params_;
  p.ls_cos2 = ls_cos2(lookup);  // the CPU's arithmetic, so both sides agree
  p.ls_behind = ls_behind_code(lookup);
  p.ls_leave_reach = lookup.leave_reach;
  return p;
}

}  // namespace ls::gpu
