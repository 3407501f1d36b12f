// Binned SAH BVH construction over axis-aligned boxes, parallel with TBB.  Used for every BVH of the
// project: object BVHs over triangles, the flat BVH over world triangles, the top level over
// instances.  The primitives are reordered so that every node covers one contiguous range.
#pragma once

#include "scene.h"
#include "kernels/layouts.h"

#include <cstdint>
#include <vector>

namespace ls {

struct BvhBuildOptions {
  int bins = 32;                 // SAH bins per axis
  int max_leaf_size = 4;         // a leaf never holds more, unless primitives cannot be separated
  float traversal_cost = 1.0f;   // relative to one primitive test
  int sah_depth_limit = 32;      // deeper, split at the object median: total depth stays < 64
};

struct BvhBuildResult {
  std::vector<lsk::BvhNode> nodes;  // root at 0; inner nodes' children adjacent
  std::vector<uint32_t> order;      // order[i] = input index of the primitive at position i
  int max_depth = 0;                // the root has depth 0
};

// boxes.size() must be >= 1.
BvhBuildResult build_bvh(const std::vector<Bounds>& boxes, const BvhBuildOptions& options = {});

}  // namespace ls
