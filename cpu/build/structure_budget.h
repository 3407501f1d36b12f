// What a structure will take, estimated from the scene and the parameters alone and refused against
// the memory budget (common/base/memory_budget.h) before any large allocation.
#pragma once

#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/structure/accel.h"

#include <cstddef>

namespace ls {

// Upper bound of the bytes of a structure: BVH nodes, triangles and ids, the build's temporary
// arrays, and for F-LS / 2L-LS the Line Space at min(2^D, triangles / min_triangles) LS nodes per
// BVH (subtrees at one depth are disjoint, so no more nodes can qualify), 4-byte candidates.
struct StructureEstimate {
  size_t bvh_bytes = 0;
  size_t ls_bytes = 0;
  size_t ls_nodes_at_most = 0;
  size_t total() const { return bvh_bytes + ls_bytes; }
};
StructureEstimate estimate_structure_bytes(const Scene& scene, const StructureSpec& spec, const AccelOptions& options);

// Throws InputError when estimate_structure_bytes() exceeds memory_budget(options.limits.max_memory).
void check_structure_budget(const Scene& scene, const StructureSpec& spec, const AccelOptions& options);

}  // namespace ls
