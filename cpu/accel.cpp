#include "accel.h"

#include "huge_pages.h"
#include "ls_budget.h"
#include "memory_budget.h"
#include "top_level_update.h"
#include "parallel.h"

#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <chrono>
#include <cmath>

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

}  // namespace

size_t Accel::bytes_ls() const {
  return node_ls.size() * sizeof(uint32_t) + ls_nodes.size() * sizeof(lsk::LsNode) +
         ls_candidates.size() * sizeof(uint32_t) + tri_normals.size() * sizeof(glm::uvec4);
}

size_t Accel::bytes_wide() const { return fast ? fast->bytes() : 0; }

size_t Accel::bytes_total() const {
  return nodes.size() * sizeof(lsk::BvhNode) + tris.size() * sizeof(lsk::Triangle) +
         tri_ids.size() * sizeof(uint32_t) + tri_instances.size() * sizeof(uint32_t) +
         top_nodes.size() * sizeof(lsk::BvhNode) + instances.size() * sizeof(lsk::InstanceRecord) + bytes_ls();
}

lsk::TraceContext Accel::context() const {
  lsk::TraceContext c;
  c.nodes = nodes.data();
  c.tris = tris.data();
  c.tri_ids = tri_ids.data();
  c.tri_instances = tri_instances.data();
  c.top_nodes = top_nodes.data();
  c.instances = instances.data();
  if (spec.line_space() && !node_ls.empty()) {  // laid out (a 2l-ls:auto plan traces before it has one)
    c.node_ls = node_ls.data();
    c.ls_nodes = ls_nodes.data();
    c.ls_candidates = ls_candidates.data();
    c.tri_normals = tri_normals.data();
    c.ls_enabled = 1;
    const double a = double(ls_options.angle_degrees) * 3.14159265358979323846 / 180.0;
    c.ls_cos2 = ls_options.angle_degrees <= 0.0f ? -1.0f : float(std::cos(a) * std::cos(a));
    c.ls_reverse = ls_options.reverse_behind ? 1u : 0u;
  }
  return c;
}

Accel build_accel(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) {
  // Refuse from the scene and parameters alone, before any large allocation (memory_budget.h).
  if (spec.budgeted && options.ls.objects.empty() && options.ls.budget == 0)
    throw InputError("structure '2l-ls:auto' needs a Line Space budget: --ls-budget MB");
  check_structure_budget(scene, spec, options.ls);
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
  double ls_layout_seconds = 0.0;
  if (spec.line_space()) {
    LsOptions ls = options.ls;
    if (spec.budgeted && ls.objects.empty()) {  // 2l-ls:auto: D and N per object, measured (ls_budget.h)
      accel.ls_plan = std::make_shared<const LsPlan>(plan_line_space_budget(scene, accel, ls));
      ls.objects = accel.ls_plan->objects(scene.meshes.size());
    }
    const auto layout_start = std::chrono::steady_clock::now();
    layout_line_space(scene, ls, accel);
    ls_layout_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - layout_start).count();
  }
  // The fast path's wide trees need the Line Space's nodes, not its candidates: made before the
  // search, which then runs on it.
  const auto wide_start = std::chrono::steady_clock::now();
  if (options.fast_path) {
    check_fast_path_budget(accel, options.wide_width, options.exact_width, options.ls.max_memory);
    accel.fast = make_fast_tracer(accel, options.wide_width, options.exact_width);
  }
  accel.traversal = options.fast_path ? options.traversal : Traversal::Reference;
  accel.wide_build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wide_start).count();
  if (spec.line_space() && options.search_candidates) {
    search_line_space(accel.ls_options, accel);  // sets ls_info.seconds to the search's
    accel.ls_info.seconds += ls_layout_seconds;
  }
  accel.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return accel;
}

lsk::Hit trace_ray_reference(lsk::TraceContext& context, const lsk::Ray& ray, bool two_level, bool any_hit) {
  return two_level ? context.trace_two_level(ray, any_hit) : context.trace_flat(ray, any_hit);
}

bool trace_bvh_reference(lsk::TraceContext& context, uint32_t root, const lsk::vec3& origin, const lsk::vec3& dir,
                         float tmin, uint32_t instance, bool any_hit, bool use_ls, lsk::Hit& hit, uint32_t& hit_prim) {
  return context.trace_bvh(root, origin, dir, tmin, instance, any_hit, use_ls, hit, hit_prim);
}

lsk::Hit trace_ray_counted(lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit) {
  return trace_ray_reference(context, ray, accel.spec.two_level(), any_hit);
}

lsk::Hit trace_ray(const lsk::TraceContext& context, const Accel& accel, const lsk::Ray& ray, bool any_hit) {
  lsk::TraceContext c = context;
  return trace_ray_counted(c, accel, ray, any_hit);
}

void add_counters(lsk::LsCounters& into, const lsk::LsCounters& from) {
  into.lookups += from.lookups;
  into.empty += from.empty;
  into.accepted += from.accepted;
  into.refused_angle += from.refused_angle;
  into.refused_behind += from.refused_behind;
  into.refused_beyond += from.refused_beyond;
  into.refused_parallel += from.refused_parallel;
  into.refused_no_shaft += from.refused_no_shaft;
}

void trace_rays(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters) {
  trace_rays(accel, rays, hits, count, any_hit, counters, accel.traversal);
}

std::vector<uint8_t> line_space_subtrees(const Accel& accel) {
  std::vector<uint8_t> in_ls;
  if (accel.node_ls.empty()) return in_ls;
  in_ls.assign(accel.nodes.size(), 0);
  std::vector<uint32_t> stack;
  for (size_t n = 0; n != accel.nodes.size(); ++n) {
    if (accel.node_ls[n] == lsk::LS_INVALID || in_ls[n]) continue;
    stack.assign(1, uint32_t(n));
    while (!stack.empty()) {
      const uint32_t i = stack.back();
      stack.pop_back();
      in_ls[i] = 1;
      const lsk::BvhNode& node = accel.nodes[i];
      if (node.count == 0) {
        stack.push_back(node.first);
        stack.push_back(node.first + 1);
      }
    }
  }
  return in_ls;
}

namespace {

// trace_rays and trace_occlusion: TBB over chunks of rays, each chunk on its own copy of the trace
// context, counters per thread and summed once.
void trace_chunks(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit, bool occlusion,
                  lsk::LsCounters* counters, Traversal traversal, TraceWorkTotals* work,
                  const std::vector<uint8_t>* ls_subtrees) {
  lsk::TraceContext context = accel.context();
  if (work && ls_subtrees && !ls_subtrees->empty()) context.node_in_ls = ls_subtrees->data();
  const FastTracer* fast = traversal == Traversal::Fast ? accel.fast.get() : nullptr;  // none: hand-made Accel
  // Per-thread counters, summed once at the end: no lock on the hot path.
  tbb::enumerable_thread_specific<lsk::LsCounters> per_thread(lsk::LsCounters{});
  tbb::enumerable_thread_specific<TraceWorkTotals> per_thread_work;
  ls::parallel_for(tbb::blocked_range<size_t>(0, count, 256), [&](const tbb::blocked_range<size_t>& r) {
    lsk::TraceContext local = context;
    if (fast && occlusion)
      fast->occluded(local, rays + r.begin(), hits + r.begin(), r.size());
    else if (fast)
      fast->trace(local, rays + r.begin(), hits + r.begin(), r.size(), any_hit);
    else
      for (size_t i = r.begin(); i != r.end(); ++i) hits[i] = trace_ray_counted(local, accel, rays[i], any_hit);
    if (counters && accel.spec.line_space()) add_counters(per_thread.local(), local.ls_counters);
    if (work) {
      TraceWorkTotals& w = per_thread_work.local();
      w.box_tests += local.trace_work.box_tests;
      w.triangle_tests += local.trace_work.triangle_tests;
      w.lookups += local.ls_counters.lookups;
      w.box_tests_in_ls += local.trace_work.box_tests_in_ls;
      w.triangle_tests_in_ls += local.trace_work.triangle_tests_in_ls;
    }
  });
  if (counters)
    for (const lsk::LsCounters& c : per_thread) add_counters(*counters, c);
  if (work)
    for (const TraceWorkTotals& w : per_thread_work) {
      work->box_tests += w.box_tests;
      work->triangle_tests += w.triangle_tests;
      work->lookups += w.lookups;
      work->box_tests_in_ls += w.box_tests_in_ls;
      work->triangle_tests_in_ls += w.triangle_tests_in_ls;
    }
}

}  // namespace

void trace_rays(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, bool any_hit,
                lsk::LsCounters* counters, Traversal traversal, TraceWorkTotals* work,
                const std::vector<uint8_t>* ls_subtrees) {
  trace_chunks(accel, rays, hits, count, any_hit, false, counters, traversal, work, ls_subtrees);
}

void trace_occlusion(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters,
                     Traversal traversal) {
  trace_chunks(accel, rays, hits, count, true, true, counters, traversal, nullptr, nullptr);
}

void trace_occlusion(const Accel& accel, const lsk::Ray* rays, lsk::Hit* hits, size_t count, lsk::LsCounters* counters) {
  trace_occlusion(accel, rays, hits, count, counters, accel.traversal);
}

}  // namespace ls
