// Binned SAH BVH construction over axis-aligned boxes, parallel with TBB.  Used for every BVH of the
// project: object BVHs over triangles, the flat BVH over world triangles, the top level over
// instances.  The primitives are reordered so that every node covers one contiguous range.
#pragma once

#include "common/kernels/layouts.h"
#include "common/model/scene.h"
#include "common/structure/accel.h"

#include <cstdint>
#include <vector>

namespace ls {

struct BvhBuildResult {
  std::vector<lsk::BvhNode> nodes;  // root at 0; inner nodes' children adjacent
  std::vector<uint32_t> order;      // order[i] = input index of the primitive at position i
  int max_depth = 0;                // the root has depth 0
};

// boxes.size() must be >= 1.
BvhBuildResult build_bvh(const std::vector<Bounds>& boxes, const BvhBuildOptions& options = {});

}  // namespace ls
