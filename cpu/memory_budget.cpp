#include "memory_budget.h"

#include "accel.h"
#include "exact_wide_bvh.h"
#include "kernels/layouts.h"
#include "kernels/line_space.h"
#include "ray_files.h"
#include "triangle_blocks.h"
#include "wide_bvh.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace ls {
namespace {

// bytes in MiB rounded by `round` (std::ceil or std::floor) to whole MiB, or to tenths below 10 MiB.
std::string mib_rounded(double bytes, double (*round)(double)) {
  const double mib = bytes / double(1 << 20);
  const double tenths = round(mib * 10.0);
  if (tenths >= 100.0) return std::to_string(uint64_t(round(mib))) + " MiB";
  const uint64_t t = uint64_t(tenths);
  std::string text = std::to_string(t / 10u);
  if (t % 10u != 0u) text += '.' + std::to_string(t % 10u);
  return text + " MiB";
}

}  // namespace

std::string mib_text(double bytes) { return mib_rounded(bytes, std::ceil); }

std::string mib_budget_text(double bytes) { return mib_rounded(bytes, std::floor); }

namespace {

// Per triangle while building: the triangle (48 B), its id and instance (8 B), its box, the builder's
// primitive reference and the order it returns (24 + 32 + 4 B, ~64 B), the flat build's world copy
// (48 B); per node 32 B, at most 2 nodes per triangle.
constexpr double kBytesPerTriangle = 48 + 8 + 64 + 48 + 2 * sizeof(lsk::BvhNode);
// A Line Space adds per triangle its octahedral vertex normals (16 B) and per BVH node its LS index.
constexpr double kLsBytesPerTriangle = sizeof(glm::uvec4) + 2 * sizeof(uint32_t);

// At most this many LS nodes in a BVH over `triangles` at depth `depth` (double: 2^60 is fine).
double ls_nodes_at_most(size_t triangles, int depth, uint32_t min_triangles) {
  return std::min(std::ldexp(1.0, depth), std::floor(double(triangles) / double(std::max<uint32_t>(1, min_triangles))));
}

}  // namespace

size_t memory_budget(size_t max_memory) { return max_memory ? max_memory : physical_memory_bytes() / 2; }

StructureEstimate estimate_structure_bytes(const Scene& scene, const StructureSpec& spec, const LsOptions& ls) {
  // Triangles each BVH holds: every world triangle (flat), or each used mesh once (two-level).
  // Each BVH with the D and N of its Line Space: the structure's, or its object's own (2L).
  struct PerBvh {
    size_t triangles;
    int depth, n;
  };
  std::vector<PerBvh> per_bvh;
  if (spec.two_level()) {
    std::vector<bool> used(scene.meshes.size(), false);
    for (const Instance& inst : scene.instances) used[inst.mesh] = true;
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
      if (!used[m]) continue;
      const ObjectLs o = ls.objects.empty() ? ObjectLs{spec.depth, spec.subdivision} : m < ls.objects.size() ? ls.objects[m] : ObjectLs{};
      per_bvh.push_back({scene.meshes[m].triangles.size(), o.depth, o.n});
    }
  } else {
    per_bvh.push_back({triangle_count(scene), spec.depth, spec.subdivision});
  }
  double bvh = 0.0, nodes = 0.0, triangles = 0.0, shafts = 0.0;
  for (const PerBvh& b : per_bvh) {
    bvh += double(b.triangles) * kBytesPerTriangle;
    triangles += double(b.triangles);
    if (spec.line_space() && b.n > 0) {
      const double k = ls_nodes_at_most(b.triangles, b.depth, ls.min_triangles);
      nodes += k;
      shafts += k * 30.0 * std::pow(double(b.n), 4.0);
    }
  }
  if (spec.two_level()) bvh += double(scene.instances.size()) * (sizeof(lsk::InstanceRecord) + 2 * sizeof(lsk::BvhNode) + 64);
  // 2l-ls:auto spends at most its budget on the Line Space (the plan's bytes are exact), and its
  // pilot holds one object's Line Space at a time, no more than the budget either.
  const bool planned = spec.budgeted && ls.objects.empty();
  const double ls_bytes = !spec.line_space() ? 0.0
                          : planned         ? double(ls.budget)
                                            : shafts * 4.0 + nodes * sizeof(lsk::LsNode) + triangles * kLsBytesPerTriangle;
  // Saturate instead of overflowing size_t (2^60 nodes of 2 GB each are representable in double).
  const double cap = double(SIZE_MAX / 4);
  StructureEstimate e;
  e.bvh_bytes = size_t(std::min(bvh, cap));
  e.ls_bytes = size_t(std::min(ls_bytes, cap));
  e.ls_nodes_at_most = size_t(std::min(nodes, cap));
  return e;
}

void check_structure_budget(const Scene& scene, const StructureSpec& spec, const LsOptions& ls) {
  const size_t budget = memory_budget(ls.max_memory);
  const StructureEstimate e = estimate_structure_bytes(scene, spec, ls);
  if (e.total() <= budget) return;
  std::string why = "structure '" + spec.name() + "' would take up to " + mib_text(double(e.total())) + " (";
  if (spec.budgeted)
    why += "Line Space budget " + mib_text(double(e.ls_bytes)) + "; ";
  else if (spec.line_space())
    why += "Line Space " + mib_text(double(e.ls_bytes)) + ": up to " + std::to_string(e.ls_nodes_at_most) + " LS nodes" +
           (ls.objects.empty() ? " x " + std::to_string(lsk::ls_shaft_count(uint32_t(spec.subdivision))) + " shafts; " : "; ");
  why += "BVH and triangles " + mib_text(double(e.bvh_bytes)) + "), over the budget of " + mib_budget_text(double(budget)) + ": ";
  why += spec.budgeted       ? "lower --ls-budget or raise --max-memory"
         : spec.line_space() ? "lower N or D, raise --ls-min-triangles, or raise --max-memory"
                             : "use a smaller scene or raise --max-memory";
  throw InputError(why);
}

namespace {

// What fast_path_bytes_at_most needs of one binary BVH array.
struct BvhShape {
  size_t nodes = 0;
  size_t inner = 0;
  size_t blocks = 0;  // ceil(count / 4) summed over the leaves
};

BvhShape bvh_shape(const std::vector<lsk::BvhNode>& nodes) {
  BvhShape s;
  s.nodes = nodes.size();
  for (const lsk::BvhNode& n : nodes)
    if (n.count > 0)
      s.blocks += (size_t(n.count) + 3u) / 4u;
    else
      ++s.inner;
  return s;
}

}  // namespace

size_t fast_path_bytes_at_most(const Accel& accel, int width, int exact_width) {
  const size_t exact_node = exact_width == 8 ? sizeof(ExactWideNode<8>) : sizeof(ExactWideNode<4>);
  const size_t treelet_node = width == 8 ? sizeof(WideNode<3>) : sizeof(WideNode<2>);
  const bool treelets = accel.spec.line_space();
  // Each order-free node is made from a distinct binary inner node (the collapse picks its lanes
  // among that node's descendants).
  const BvhShape object = bvh_shape(accel.nodes);
  size_t bytes = object.inner * exact_node + object.blocks * sizeof(TriBlock) +
                 2 * object.nodes * sizeof(uint32_t);  // entry_of, lane_of
  if (treelets) bytes += object.inner * treelet_node + object.nodes * sizeof(uint32_t);  // wide_of
  if (accel.spec.two_level()) {
    const BvhShape top = bvh_shape(accel.top_nodes);
    bytes += top.inner * exact_node + top.nodes * sizeof(uint32_t);
    if (treelets) bytes += top.inner * treelet_node + top.nodes * sizeof(uint32_t);
  }
  return bytes;
}

void check_fast_path_budget(const Accel& accel, int width, int exact_width, size_t max_memory) {
  const size_t budget = memory_budget(max_memory);
  const size_t built = accel.bytes_total();
  const size_t fast = fast_path_bytes_at_most(accel, width, exact_width);
  if (built <= budget && fast <= budget - built) return;
  throw InputError("the fast path of structure '" + accel.spec.name() + "' (its wide trees and triangle blocks) would take up to " +
                   mib_text(double(fast)) + " beside the structure's " + mib_text(double(built)) + ", over the budget of " +
                   mib_budget_text(double(budget)) + ": use a smaller scene, --exact-width 4, or raise --max-memory");
}

size_t ray_bytes(size_t count, bool made, int hits) {
  const size_t held = sizeof(lsk::Ray) + size_t(hits) * sizeof(lsk::Hit);
  const size_t making = 2 * sizeof(lsk::Ray) + 1;
  return count * (made ? std::max(held, making) : held);
}

void check_held_budget(const std::string& what, size_t bytes, size_t max_memory, const std::string& remedy) {
  const size_t budget = memory_budget(max_memory);
  if (bytes <= budget) return;
  throw InputError(what + " take up to " + mib_text(double(bytes)) + ", over the budget of " + mib_budget_text(double(budget)) +
                   ": " + remedy);
}

void check_ray_budget(const std::string& command, const std::string& rays_path, size_t count, int hits, size_t max_memory) {
  const bool made = rays_path.empty();
  if (!made) count = ray_file_count(rays_path);
  check_held_budget(command + ": " + std::to_string(count) + " rays" + (hits > 0 ? " and their hits" : ""),
                    ray_bytes(count, made, hits), max_memory,
                    made ? "use fewer rays (--count) or raise --max-memory" : "use a smaller ray file or raise --max-memory");
}

size_t estimate_render_bytes(uint32_t width, uint32_t height, int bounces) {
  // Per pixel: bounce images and the total (12 B each), path state, hit, batch ray and hit, shadow
  // query, flags and counters (~170 B), the PNG's 3 bytes and one EXR conversion copy (12 B).
  const double per_pixel = 12.0 * double(bounces + 2) + 170.0 + 3.0 + 12.0;
  return size_t(double(width) * double(height) * per_pixel);
}

void check_render_budget(uint32_t width, uint32_t height, int bounces, size_t max_memory) {
  const size_t budget = memory_budget(max_memory);
  const size_t estimate = estimate_render_bytes(width, height, bounces);
  if (estimate <= budget) return;
  throw InputError("render " + std::to_string(width) + "x" + std::to_string(height) + " with " + std::to_string(bounces) +
                   " bounces would take about " + mib_text(double(estimate)) + " of image buffers, over the budget of " +
                   mib_budget_text(double(budget)) + ": lower --size or --bounces, or raise --max-memory");
}

}  // namespace ls
