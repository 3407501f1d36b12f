// The C++ stand-in for a shader's bound buffers: the single-source traversal kernels are included
// inside this struct, so `nodes[i]` in the kernel reads the pointer member here and the buffer there.
#pragma once

#include "kernels/layouts.h"
#include "kernels/ray_box.h"
#include "kernels/ray_triangle.h"

namespace lsk {

struct TraceContext {
  const BvhNode* nodes = nullptr;
  const Triangle* tris = nullptr;
  const uint* tri_ids = nullptr;
  const uint* tri_instances = nullptr;
  const BvhNode* top_nodes = nullptr;
  const InstanceRecord* instances = nullptr;

#include "kernels/traverse_bvh.h"
};

}  // namespace lsk
