#include "cpu/build/build_accel.h"

#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "cpu/build/bvh_builder.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/build/structure_budget.h"
#include "cpu/build/top_level_update.h"
#include "cpu/trace/fast_path_budget.h"
#include "cpu/trace/fast_tracer.h"

#include <algorithm>
#include <atomic>
#include <chrono>

namespace ls {
namespace {

Bounds triangle_bounds(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  Bounds box;
  box.grow(a);
  box.grow(b);
  box.grow(c);
  return box;
}

lsk::Triangle make_triangle(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  lsk::Triangle t;
  t.v0 = glm::vec4(a, 0.0f);
  t.v1 = glm::vec4(b, 0.0f);
  t.v2 = glm::vec4(c, 0.0f);
  return t;
}

// Which meshes some instance uses: the structures hold only those.
std::vector<bool> used_meshes(const Scene& scene) {
  std::vector<bool> used(scene.meshes.size(), false);
  for (const Instance& inst : scene.instances) used[inst.mesh] = true;
  return used;
}

void build_flat(const Scene& scene, const BvhBuildOptions& options, Accel& accel) {
  // World-space triangles, instance by instance in id order.
  std::vector<size_t> first(scene.instances.size() + 1, 0);
  for (size_t i = 0; i < scene.instances.size(); ++i)
    first[i + 1] = first[i] + scene.meshes[scene.instances[i].mesh].triangles.size();
  const size_t total = first.back();
  std::vector<lsk::Triangle> world;
  std::vector<Bounds> boxes;
  std::vector<uint32_t> instance_of;  // each world triangle's instance: no search per triangle below
  resize_huge(world, total);
  resize_huge(boxes, total);
  resize_huge(instance_of, total);
  ls::parallel_for(size_t(0), scene.instances.size(), [&](size_t i) {
    const Instance& inst = scene.instances[i];
    const Mesh& mesh = scene.meshes[inst.mesh];
    ls::parallel_for(size_t(0), mesh.triangles.size(), [&](size_t t) {
      const glm::uvec3 idx = mesh.triangles[t];
      const glm::vec3 a = transform_point(inst.object_to_world, mesh.positions[idx.x]);
      const glm::vec3 b = transform_point(inst.object_to_world, mesh.positions[idx.y]);
      const glm::vec3 c = transform_point(inst.object_to_world, mesh.positions[idx.z]);
      world[first[i] + t] = make_triangle(a, b, c);
      boxes[first[i] + t] = triangle_bounds(a, b, c);
      instance_of[first[i] + t] = uint32_t(i);
    });
  });
  BvhBuildResult bvh = build_bvh(boxes, options);
  accel.nodes = std::move(bvh.nodes);
  accel.max_depth = bvh.max_depth;
  resize_huge(accel.tris, total);
  resize_huge(accel.tri_ids, total);
  resize_huge(accel.tri_instances, total);
  ls::parallel_for(size_t(0), total, [&](size_t k) {
    const size_t src = bvh.order[k];
    const uint32_t inst = instance_of[src];
    accel.tris[k] = world[src];
    accel.tri_ids[k] = uint32_t(src - first[inst]);
    accel.tri_instances[k] = inst;
  });
  const std::vector<bool> used = used_meshes(scene);
  accel.objects = size_t(std::count(used.begin(), used.end(), true));
}

void build_two_level(const Scene& scene, const BvhBuildOptions& options, Accel& accel) {
  const std::vector<bool> used = used_meshes(scene);

  // One BVH per unique mesh, in object space, built in parallel.
  std::vector<BvhBuildResult> object_bvh(scene.meshes.size());
  ls::parallel_for(size_t(0), scene.meshes.size(), [&](size_t m) {
    const Mesh& mesh = scene.meshes[m];
    if (!used[m] || mesh.triangles.empty()) return;
    std::vector<Bounds> boxes(mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::uvec3 idx = mesh.triangles[t];
      boxes[t] = triangle_bounds(mesh.positions[idx.x], mesh.positions[idx.y], mesh.positions[idx.z]);
    }
    object_bvh[m] = build_bvh(boxes, options);
  });

  // Concatenate: node and triangle indices become absolute.
  accel.object_roots.assign(scene.meshes.size(), lsk::LS_INVALID);
  size_t node_total = 0, tri_total = 0;
  for (const BvhBuildResult& b : object_bvh) {
    node_total += b.nodes.size();
    tri_total += b.order.size();
  }
  reserve_huge(accel.nodes, node_total);
  reserve_huge(accel.tris, tri_total);
  reserve_huge(accel.tri_ids, tri_total);
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    if (object_bvh[m].nodes.empty()) continue;
    const Mesh& mesh = scene.meshes[m];
    const uint32_t node_base = uint32_t(accel.nodes.size());
    const uint32_t tri_base = uint32_t(accel.tris.size());
    accel.object_roots[m] = node_base;
    for (lsk::BvhNode node : object_bvh[m].nodes) {
      node.first += node.count > 0 ? tri_base : node_base;
      accel.nodes.push_back(node);
    }
    for (uint32_t src : object_bvh[m].order) {
      const glm::uvec3 idx = mesh.triangles[src];
      accel.tris.push_back(make_triangle(mesh.positions[idx.x], mesh.positions[idx.y], mesh.positions[idx.z]));
      accel.tri_ids.push_back(src);
    }
    accel.max_depth = std::max(accel.max_depth, object_bvh[m].max_depth);
    ++accel.objects;
  }

  // The top level over instance boxes (each object's root box carried into the world).
  build_top_level(scene, options, accel);
}

// A 2l-ls:auto structure is built from its plan (options.ls.objects), which build_accel never makes.
void require_plan(const StructureSpec& spec, const AccelOptions& options) {
  if (spec.budgeted && options.ls.objects.empty())
    throw InputError("structure '2l-ls:auto' needs its plan before it is built (build_planned_accel, build_structures.h)");
}

}  // namespace

Accel build_bvhs(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) {
  // Refuse from the scene and parameters alone, before any large allocation (structure_budget.h).
  check_structure_budget(scene, spec, options);
  const auto start = std::chrono::steady_clock::now();
  Accel accel;
  static std::atomic<uint64_t> builds{0};
  accel.build_id = ++builds;
  accel.spec = spec;
  accel.bvh_options = options.bvh;
  accel.instance_count = scene.instances.size();
  accel.world_triangles = triangle_count(scene);
  if (spec.two_level())
    build_two_level(scene, options.bvh, accel);
  else
    build_flat(scene, options.bvh, accel);
  accel.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return accel;
}

void finish_accel(const Scene& scene, const AccelOptions& options, Accel& accel) {
  const StructureSpec& spec = accel.spec;
  require_plan(spec, options);
  const auto start = std::chrono::steady_clock::now();
  double ls_layout_seconds = 0.0;
  if (spec.line_space()) {
    layout_line_space(scene, options.ls, options.limits, accel);
    ls_layout_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  // The fast path's wide trees need the Line Space's nodes, not its candidates: made before the
  // search, which then runs on it.
  const auto wide_start = std::chrono::steady_clock::now();
  if (options.fast_path) {
    check_fast_path_budget(accel, options.exact_width, options.limits.max_memory);
    accel.fast = make_fast_tracer(accel, options.exact_width);
    accel.fast_bytes = accel.fast->bytes();
  }
  accel.traversal = options.fast_path ? options.traversal : Traversal::Reference;
  accel.wide_build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wide_start).count();
  if (spec.line_space() && options.search_candidates) {
    search_line_space(accel.ls_options, accel);  // sets ls_info.seconds to the search's
    accel.ls_info.seconds += ls_layout_seconds;
  }
  accel.build_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Accel build_accel(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) {
  require_plan(spec, options);
  Accel accel = build_bvhs(scene, spec, options);
  finish_accel(scene, options, accel);
  return accel;
}

}  // namespace ls
