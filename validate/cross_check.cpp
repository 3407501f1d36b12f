#include "validate/cross_check.h"

#include "common/base/memory_budget.h"
#include "common/base/ray_files.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"
#include "gpu/gpu_accel.h"
#include "gpu/gpu_line_space.h"
#include "gpu/gpu_trace.h"
#include "scenes/load_scene.h"

#include <cstring>

namespace ls::validate {
namespace {

void note(CrossCheckResult& r, size_t max_listed, std::string where, std::string cpu, std::string gpu) {
  ++r.mismatches;
  if (r.first.size() < max_listed) r.first.push_back({std::move(where), std::move(cpu), std::move(gpu)});
}

std::string candidate_text(uint32_t prim) { return prim == lsk::LS_INVALID ? "empty" : "triangle " + std::to_string(prim); }

std::string hex(uint32_t bits) {
  char s[16];
  std::snprintf(s, sizeof(s), "%08x", bits);
  return s;
}

std::string hit_text(const lsk::Hit& h) {
  uint32_t t, u, v;
  std::memcpy(&t, &h.t, 4);
  std::memcpy(&u, &h.u, 4);
  std::memcpy(&v, &h.v, 4);
  char s[160];
  std::snprintf(s, sizeof(s), "t=%.9g (0x%s) instance=%d triangle=%d u=0x%s v=0x%s", double(h.t), hex(t).c_str(), int(h.instance),
                int(h.triangle), hex(u).c_str(), hex(v).c_str());
  return s;
}

std::string counters_text(const lsk::LsCounters& c) {
  return "lookups " + std::to_string(c.lookups) + ", empty " + std::to_string(c.empty) + ", accepted " + std::to_string(c.accepted) +
         ", refused " + std::to_string(c.refused_angle) + "/" + std::to_string(c.refused_behind) + "/" +
         std::to_string(c.refused_beyond) + "/" + std::to_string(c.refused_parallel) + "/" + std::to_string(c.refused_no_shaft);
}

}  // namespace

CrossCheckResult compare_candidate_arrays(const Accel& cpu, const Accel& gpu, size_t max_listed) {
  CrossCheckResult r;
  if (cpu.ls_nodes.size() != gpu.ls_nodes.size() || cpu.ls_info.shafts != gpu.ls_info.shafts) {
    note(r, max_listed, "layout", std::to_string(cpu.ls_nodes.size()) + " LS nodes", std::to_string(gpu.ls_nodes.size()) + " LS nodes");
    return r;
  }
  lsk::TraceContext c = trace_context(cpu), g = trace_context(gpu);  // candidates: no lookup
  for (size_t i = 0; i < cpu.ls_nodes.size(); ++i) {
    const lsk::LsNode& a = cpu.ls_nodes[i];
    const lsk::LsNode& b = gpu.ls_nodes[i];
    const uint32_t shafts = lsk::ls_shaft_count(a.n);
    if (std::memcmp(&a, &b, sizeof(a)) != 0) {
      note(r, max_listed, "LS node " + std::to_string(i) + " header", "BVH node " + std::to_string(a.node),
           "BVH node " + std::to_string(b.node) + " (headers differ)");
      continue;
    }
    for (uint32_t s = 0; s < shafts; ++s) {
      ++r.compared;
      const uint32_t x = c.ls_candidate(a, s), y = g.ls_candidate(b, s);
      if (x != y)
        note(r, max_listed, "LS node " + std::to_string(i) + " (BVH node " + std::to_string(a.node) + ") shaft " + std::to_string(s),
             candidate_text(x), candidate_text(y));
    }
  }
  // The stored words too (padding of the last word of a node included).
  if (cpu.ls_candidates.size() != gpu.ls_candidates.size())
    note(r, max_listed, "candidate words", std::to_string(cpu.ls_candidates.size()), std::to_string(gpu.ls_candidates.size()));
  else
    for (size_t w = 0; w < cpu.ls_candidates.size(); ++w)
      if (cpu.ls_candidates[w] != gpu.ls_candidates[w]) {
        note(r, max_listed, "candidate word " + std::to_string(w), hex(cpu.ls_candidates[w]), hex(gpu.ls_candidates[w]));
        break;  // the shafts above already name the difference
      }
  if (cpu.ls_info.empty_shafts != gpu.ls_info.empty_shafts)
    note(r, max_listed, "empty shafts", std::to_string(cpu.ls_info.empty_shafts), std::to_string(gpu.ls_info.empty_shafts));
  return r;
}

CrossCheckResult compare_hit_arrays(const std::vector<lsk::Hit>& cpu, const std::vector<lsk::Hit>& gpu, const lsk::LsCounters& cpu_counters,
                                    const lsk::LsCounters& gpu_counters, size_t max_listed) {
  CrossCheckResult r;
  if (cpu.size() != gpu.size()) {
    note(r, max_listed, "hit count", std::to_string(cpu.size()), std::to_string(gpu.size()));
    return r;
  }
  for (size_t i = 0; i < cpu.size(); ++i) {
    ++r.compared;
    if (std::memcmp(&cpu[i], &gpu[i], sizeof(lsk::Hit)) != 0) note(r, max_listed, "ray " + std::to_string(i), hit_text(cpu[i]), hit_text(gpu[i]));
  }
  if (std::memcmp(&cpu_counters, &gpu_counters, sizeof(lsk::LsCounters)) != 0)
    note(r, max_listed, "Line Space counters", counters_text(cpu_counters), counters_text(gpu_counters));
  return r;
}

CrossCheckResult cross_check_candidates(const gpu::VulkanContext& context, const Scene& scene, const StructureSpec& spec,
                                        const AccelOptions& options) {
  if (!spec.line_space()) throw InputError("candidates: structure '" + spec.name() + "' has no Line Space (use f-ls:D:N or 2l-ls:D:N)");
  const Accel cpu = build_planned_accel(scene, spec, options);
  // A check of no shaft would pass saying "0 compared".
  if (cpu.ls_nodes.empty())
    throw InputError("candidates: '" + spec.name() + "' has no Line Space node on this scene (none of its subtrees at depth D "
                     "holds --ls-min-triangles, or --scale/--offset collapsed it): nothing to compare");
  const Accel gpu = gpu::build_accel_gpu(context, scene, spec, options);
  return compare_candidate_arrays(cpu, gpu);
}

CrossCheckResult cross_check_hits(const gpu::VulkanContext& context, const Scene& scene, const StructureSpec& spec,
                                  const std::vector<lsk::Ray>& rays, bool any_hit, const AccelOptions& options,
                                  const LsLookup& lookup) {
  const Accel accel = build_planned_accel(scene, spec, options);
  // The CPU's reference kernel walks the device's order, so its Line Space counters are the device's
  // too; the fast path walks order-free, so only its hits are compared.
  std::vector<lsk::Hit> cpu(rays.size());
  lsk::LsCounters cpu_counters{}, gpu_counters{};
  trace_rays(accel, lookup, rays.data(), cpu.data(), rays.size(), any_hit, &cpu_counters, Traversal::Reference);
  gpu::GpuAccel uploaded(context, accel);
  gpu::GpuTracer tracer(context);
  tracer.set_rays(rays);
  const std::vector<lsk::Hit> gpu = tracer.trace(uploaded, lookup, any_hit, accel.spec.line_space() ? &gpu_counters : nullptr);
  CrossCheckResult r = compare_hit_arrays(cpu, gpu, cpu_counters, gpu_counters);
  if (accel.fast) {
    std::vector<lsk::Hit> fast(rays.size());
    trace_rays(accel, lookup, rays.data(), fast.data(), rays.size(), any_hit, nullptr, Traversal::Fast);
    const CrossCheckResult f = compare_hit_arrays(fast, gpu, {}, {});
    r.mismatches += f.mismatches;
    for (const auto& m : f.first)
      if (r.first.size() < 10) r.first.push_back({"fast path, " + m.where, m.cpu, m.gpu});
  }
  return r;
}

void print_cross_check(std::FILE* out, const std::string& what, const CrossCheckResult& result) {
  std::fprintf(out, "%s: %zu compared, %zu mismatches%s\n", what.c_str(), result.compared, result.mismatches,
               result.ok() ? "" : " (first listed: where: cpu | gpu)");
  for (const Mismatch& m : result.first) std::fprintf(out, "  %s: %s | %s\n", m.where.c_str(), m.cpu.c_str(), m.gpu.c_str());
}

namespace {

Scene command_scene(const CrossCheckCommand& c) {
  Scene scene = load_scene(c.scene);
  if (c.scale != 1.0f || c.offset[0] != 0.0f || c.offset[1] != 0.0f || c.offset[2] != 0.0f)
    scale_and_offset(scene, c.scale, glm::vec3(c.offset[0], c.offset[1], c.offset[2]));
  return scene;
}

std::string label(const CrossCheckCommand& c, const gpu::VulkanContext& context) {
  std::string s = c.scene + " " + c.structure;
  if (c.scale != 1.0f) {
    char text[32];
    std::snprintf(text, sizeof(text), " scale %g", double(c.scale));
    s += text;
  }
  if (c.offset[0] != 0.0f || c.offset[1] != 0.0f || c.offset[2] != 0.0f) s += " offset";
  return s + " on " + context.description();
}

}  // namespace

int run_candidates_command(const CrossCheckCommand& command, const AccelOptions& options) {
  const Scene scene = command_scene(command);
  const StructureSpec spec = parse_structure(command.structure);
  const gpu::VulkanContext context(command.device);
  const CrossCheckResult r = cross_check_candidates(context, scene, spec, options);
  print_cross_check(stdout, "candidates, " + label(command, context) + " (shafts)", r);
  return r.ok() ? 0 : 1;
}

int run_hits_command(const CrossCheckCommand& command, const AccelOptions& options, const LsLookup& lookup) {
  check_ray_budget("hits", command.rays, command.count, 2, options.limits.max_memory);  // the CPU's hits and the GPU's
  const Scene scene = command_scene(command);
  const StructureSpec spec = parse_structure(command.structure);
  std::vector<lsk::Ray> rays;
  if (!command.rays.empty()) {
    rays = read_rays(command.rays);
  } else {
    const RayKind kind = parse_ray_kind(command.kind);
    rays = generate_rays(scene, build_accel(scene, parse_structure("bvh")), kind, command.count, command.seed);
  }
  if (rays.empty()) throw InputError("hits: no rays to trace");
  const gpu::VulkanContext context(command.device);
  const CrossCheckResult r = cross_check_hits(context, scene, spec, rays, command.any_hit, options, lookup);
  print_cross_check(stdout, std::string("hits (") + (command.any_hit ? "any hit" : "closest hit") + "), " + label(command, context) +
                                " (rays)", r);
  return r.ok() ? 0 : 1;
}

}  // namespace ls::validate
