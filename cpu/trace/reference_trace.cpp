#include "cpu/trace/reference_trace.h"

namespace ls {

lsk::Hit trace_ray_reference(lsk::TraceContext& context, const lsk::Ray& ray, bool two_level, bool any_hit) {
  return two_level ? context.trace_two_level(ray, any_hit) : context.trace_flat(ray, any_hit);
}

bool trace_bvh_reference(lsk::TraceContext& context, uint32_t root, const lsk::vec3& origin, const lsk::vec3& dir,
                         float tmin, float tmax, uint32_t instance, bool any_hit, bool use_ls, lsk::Hit& hit, uint32_t& hit_prim) {
  return context.trace_bvh(root, origin, dir, tmin, tmax, instance, any_hit, use_ls, hit, hit_prim);
}

}  // namespace ls
