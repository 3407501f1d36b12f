// An acceleration structure ready to trace: the flat BVH (F-BVH) over world-space triangles, or the
// two-level BVH (2L-BVH): one BVH per unique mesh in object space plus a top-level BVH over instances.
// The arrays are the std430 buffers the GPU port uploads unchanged.
#pragma once

#include "bvh_builder.h"
#include "scene.h"
#include "structure_name.h"
#include "trace_context.h"

#include <cstddef>
#include <vector>

namespace ls {

struct Accel {
  StructureSpec spec;
  std::vector<lsk::BvhNode> nodes;          // F: the flat BVH; 2L: every object BVH, one after another
  std::vector<lsk::Triangle> tris;          // in BVH order
  std::vector<uint32_t> tri_ids;            // triangle id within its mesh
  std::vector<uint32_t> tri_instances;      // F only: instance id per triangle
  std::vector<lsk::BvhNode> top_nodes;      // 2L only
  std::vector<lsk::InstanceRecord> instances;  // 2L only, in top-level order
  std::vector<uint32_t> object_roots;       // 2L only: root node of each unique mesh's BVH (by mesh index;
                                            // LS_INVALID for meshes no instance uses)
  size_t objects = 0;                       // unique meshes the structure holds
  size_t instance_count = 0;
  size_t world_triangles = 0;
  int max_depth = 0;                        // deepest BVH (object BVHs for 2L)
  double build_seconds = 0.0;

  size_t bytes_total() const;
  size_t bytes_ls() const { return 0; }
  lsk::TraceContext context() const;
};

// Builds F-BVH or 2L-BVH.  Line Space structures throw InputError until they are implemented.
Accel build_accel(const Scene& scene, const StructureSpec& spec, const BvhBuildOptions& options = {});

lsk::Hit trace_ray(const lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit);

// Traces a batch on all threads (TBB).
void trace_rays(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit);

}  // namespace ls
