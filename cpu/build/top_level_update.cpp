#include "cpu/build/top_level_update.h"

#include "common/structure/accel.h"
#include "common/structure/top_level.h"
#include "cpu/build/bvh_builder.h"
#include "cpu/trace/fast_tracer.h"

#include <chrono>

namespace ls {
namespace {

Bounds instance_box(const Scene& scene, const Accel& accel, uint32_t id) {
  const Instance& inst = scene.instances[id];
  const lsk::BvhNode& root = accel.nodes[accel.object_roots[inst.mesh]];
  return transform_bounds(inst.object_to_world, Bounds{root.lo, root.hi});
}

// The world-to-object rows of the instance (inverted in double, rounded once).
void set_transform(const Instance& inst, lsk::InstanceRecord& rec) {
  const glm::mat4 w2o = glm::mat4(glm::inverse(glm::dmat4(inst.object_to_world)));
  rec.world_to_object0 = glm::vec4(w2o[0][0], w2o[1][0], w2o[2][0], w2o[3][0]);
  rec.world_to_object1 = glm::vec4(w2o[0][1], w2o[1][1], w2o[2][1], w2o[3][1]);
  rec.world_to_object2 = glm::vec4(w2o[0][2], w2o[1][2], w2o[2][2], w2o[3][2]);
}

// The old tree, every box recomputed: leaves from their instances, inner nodes from their children
// (which always follow their parent in the array).
void refit(const Scene& scene, Accel& accel) {
  for (lsk::InstanceRecord& rec : accel.instances) set_transform(scene.instances[rec.instance], rec);
  for (size_t i = accel.top_nodes.size(); i-- > 0;) {
    lsk::BvhNode& node = accel.top_nodes[i];
    Bounds box;
    if (node.count > 0) {
      for (uint32_t k = node.first; k < node.first + node.count; ++k) box.grow(instance_box(scene, accel, accel.instances[k].instance));
    } else {
      for (uint32_t c = node.first; c < node.first + 2; ++c) {
        box.grow(accel.top_nodes[c].lo);
        box.grow(accel.top_nodes[c].hi);
      }
    }
    node.lo = box.lo;
    node.hi = box.hi;
  }
}

}  // namespace

void build_top_level(const Scene& scene, const BvhBuildOptions& options, Accel& accel) {
  std::vector<Bounds> boxes;
  boxes.reserve(scene.instances.size());
  for (uint32_t id = 0; id < uint32_t(scene.instances.size()); ++id) boxes.push_back(instance_box(scene, accel, id));
  BvhBuildResult top = build_bvh(boxes, options);
  accel.top_nodes = std::move(top.nodes);
  accel.instances.clear();
  accel.instances.reserve(top.order.size());
  for (uint32_t id : top.order) {
    const Instance& inst = scene.instances[id];
    lsk::InstanceRecord rec;
    set_transform(inst, rec);
    rec.root = accel.object_roots[inst.mesh];
    rec.instance = id;
    rec.object = inst.mesh;
    rec.pad = 0;
    accel.instances.push_back(rec);
  }
}

TopLevelUpdate update_top_level(const Scene& posed, Accel& accel, TopLevelMode mode) {
  const auto start = std::chrono::steady_clock::now();
  if (!accel.spec.two_level())
    throw InputError("structure '" + accel.spec.name() + "' is flat: it has no top level to update (rebuild it)");
  if (posed.instances.size() != accel.instance_count || accel.instances.size() != accel.instance_count)
    throw InputError("the posed scene has " + std::to_string(posed.instances.size()) + " instances, the structure " +
                     std::to_string(accel.instance_count));
  for (const lsk::InstanceRecord& rec : accel.instances)
    if (posed.instances[rec.instance].mesh != rec.object)
      throw InputError("instance " + std::to_string(rec.instance) + " of the posed scene places another mesh than the structure's");
  if (mode == TopLevelMode::Rebuild) build_top_level(posed, accel.bvh_options, accel);
  else refit(posed, accel);
  const auto wide_start = std::chrono::steady_clock::now();
  if (accel.fast) {
    accel.fast = accel.fast->with_top_level(accel);
    accel.fast_bytes = accel.fast->bytes();
  }
  const auto end = std::chrono::steady_clock::now();
  ++accel.top_level_version;
  TopLevelUpdate u;
  u.seconds = std::chrono::duration<double>(end - start).count();
  u.wide_seconds = std::chrono::duration<double>(end - wide_start).count();
  u.top_nodes = accel.top_nodes.size();
  return u;
}

}  // namespace ls
