// The scalar single-source kernels (common/kernels/traverse_bvh.h) on one ray, out of line.
#pragma once

#include "common/structure/trace_context.h"

#include <cstdint>

namespace ls {

// The reference kernels on one ray (flat or two-level) and on one BVH (an object-space ray), for the
// fast path's fallbacks (fast_tracer.h) and trace_rays.h.  Compiled here, not in the tracers' units
// (wide_tracer.h): the kernels instantiated there took GCC's inlining budget from the fast walks
// (5 % more instructions a ray).
lsk::Hit trace_ray_reference(lsk::TraceContext& context, const lsk::Ray& ray, bool two_level, bool any_hit);
bool trace_bvh_reference(lsk::TraceContext& context, uint32_t root, const lsk::vec3& origin, const lsk::vec3& dir,
                         float tmin, float tmax, uint32_t instance, bool any_hit, bool use_ls, lsk::Hit& hit, uint32_t& hit_prim);

}  // namespace ls
