// CPU-versus-GPU cross-checks: the Line Space candidates of every shaft of every LS node,
// and traced hits (ids and the bits of t, u, v), must be identical on both back ends (docs/design.md §5).
#pragma once

#include "common/structure/accel.h"
#include "gpu/vk_context.h"

#include <cstdio>
#include <string>
#include <vector>

namespace ls::validate {

struct Mismatch {
  std::string where;  // "LS node 3 (BVH node 17) shaft 1234", "ray 42", ...
  std::string cpu, gpu;
};

struct CrossCheckResult {
  size_t compared = 0;               // shafts or rays
  size_t mismatches = 0;
  std::vector<Mismatch> first;       // the first few, in order
  bool ok() const { return mismatches == 0; }
};

// Compares two builds of one structure shaft by shaft (decoded candidates), then their layouts and
// raw candidate words.  Pure: the tests feed it tampered copies to show it can fail.
CrossCheckResult compare_candidate_arrays(const Accel& cpu, const Accel& gpu, size_t max_listed = 10);

// Compares hits record by record (all 20 bytes: t, instance, triangle, u, v) and the LS counters.
CrossCheckResult compare_hit_arrays(const std::vector<lsk::Hit>& cpu, const std::vector<lsk::Hit>& gpu,
                                    const lsk::LsCounters& cpu_counters, const lsk::LsCounters& gpu_counters,
                                    size_t max_listed = 10);

// Builds the structure with the candidate search on the CPU and on the GPU and compares.
CrossCheckResult cross_check_candidates(const gpu::VulkanContext& context, const Scene& scene, const StructureSpec& spec,
                                        const AccelOptions& options = {});

// Builds the structure once (CPU candidates, so a candidate difference cannot hide a traversal one)
// and traces the rays on both back ends: the device's hits and counters against the CPU reference
// kernel's, and its hits against the CPU fast path's.
CrossCheckResult cross_check_hits(const gpu::VulkanContext& context, const Scene& scene, const StructureSpec& spec,
                                  const std::vector<lsk::Ray>& rays, bool any_hit, const AccelOptions& options = {},
                                  const LsLookup& lookup = {});

// "what: N compared, M mismatches" and the first mismatches, one per line.
void print_cross_check(std::FILE* out, const std::string& what, const CrossCheckResult& result);

// The `candidates` and `hits` subcommands of linespace-validate.
struct CrossCheckCommand {
  std::string scene = "builtin:cornell";
  std::string structure = "f-ls:4:6";
  std::string device;               // Vulkan device: index or part of its name (empty: preferred)
  std::string rays;                 // hits: a ray file; empty: `count` rays of `kind` made here
  std::string kind = "diffuse";
  size_t count = 100000;
  uint32_t seed = 1;
  bool any_hit = false;
  float scale = 1.0f;               // applied to the scene first (numerical extremes)
  float offset[3] = {0.0f, 0.0f, 0.0f};
};
// Print the counts and first mismatches; return 0 when identical, 1 otherwise (InputError: bad input).
int run_candidates_command(const CrossCheckCommand& command, const AccelOptions& options);
int run_hits_command(const CrossCheckCommand& command, const AccelOptions& options, const LsLookup& lookup);

}  // namespace ls::validate
