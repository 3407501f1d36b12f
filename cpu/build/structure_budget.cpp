#include "cpu/build/structure_budget.h"

#include "common/base/memory_budget.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/build/ls_budget_menu.h"

#include <algorithm>
#include <cmath>

namespace ls {
namespace {

// Per triangle while building: the triangle (48 B), its id and instance (8 B), its box, the builder's
// primitive reference and the order it returns (24 + 32 + 4 B, ~64 B), the flat build's world copy
// (48 B); per node 32 B, at most 2 nodes per triangle.
constexpr double kBytesPerTriangle = 48 + 8 + 64 + 48 + 2 * sizeof(lsk::BvhNode);
// A Line Space adds per triangle its candidate record (64 B) and per BVH node its LS index.
constexpr double kLsBytesPerTriangle = sizeof(lsk::LsRecord) + 2 * sizeof(uint32_t);

// At most this many LS nodes in a BVH over `triangles` at depth `depth` (double: 2^60 is fine).
double ls_nodes_at_most(size_t triangles, int depth, uint32_t min_triangles) {
  return std::min(std::ldexp(1.0, depth), std::floor(double(triangles) / double(std::max<uint32_t>(1, min_triangles))));
}

}  // namespace

StructureEstimate estimate_structure_bytes(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) {
  const LsBuildOptions& ls = options.ls;
  // Triangles each BVH holds: every world triangle (flat), or each used mesh once (two-level).
  // Each BVH with the D and N of its Line Space: the structure's, or its object's own (2L).
  struct PerBvh {
    size_t triangles;
    int depth, n;
  };
  // 2l-ls:auto before its plan: every object at the menu's largest D and N bounds any plan.
  const bool planned = spec.budgeted && ls.objects.empty();
  const ObjectLs largest{*std::max_element(kLsBudgetDepths.begin(), kLsBudgetDepths.end()),
                         *std::max_element(kLsBudgetSubdivisions.begin(), kLsBudgetSubdivisions.end())};
  std::vector<PerBvh> per_bvh;
  if (spec.two_level()) {
    std::vector<bool> used(scene.meshes.size(), false);
    for (const Instance& inst : scene.instances) used[inst.mesh] = true;
    for (size_t m = 0; m < scene.meshes.size(); ++m) {
      if (!used[m]) continue;
      const ObjectLs o = planned               ? largest
                         : ls.objects.empty() ? ObjectLs{spec.depth, spec.subdivision}
                         : m < ls.objects.size() ? ls.objects[m]
                                                 : ObjectLs{};
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
  // 2l-ls:auto spends at most its budget on the Line Space (the plan's bytes are exact), and no more
  // than the largest plan of its menu; its pilot holds one object's Line Space at a time, no more.
  const double largest_ls = shafts * 4.0 + nodes * sizeof(lsk::LsNode) + triangles * kLsBytesPerTriangle;
  const double ls_bytes = !spec.line_space() ? 0.0 : planned ? std::min(double(options.plan.budget), largest_ls) : largest_ls;
  // Saturate instead of overflowing size_t (2^60 nodes of 2 GB each are representable in double).
  const double cap = double(SIZE_MAX / 4);
  StructureEstimate e;
  e.bvh_bytes = size_t(std::min(bvh, cap));
  e.ls_bytes = size_t(std::min(ls_bytes, cap));
  e.ls_nodes_at_most = size_t(std::min(nodes, cap));
  return e;
}

void check_structure_budget(const Scene& scene, const StructureSpec& spec, const AccelOptions& options) {
  const LsBuildOptions& ls = options.ls;
  const size_t budget = memory_budget(options.limits.max_memory);
  const StructureEstimate e = estimate_structure_bytes(scene, spec, options);
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

}  // namespace ls
