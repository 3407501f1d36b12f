// Memory budgets: the estimates are upper bounds of what the structures really take, and over-budget
// structures and renders are refused from the parameters alone (fast, before allocating).
#include "accel.h"
#include "load_scene.h"
#include "memory_budget.h"

#include <catch2/catch.hpp>

#include <chrono>

using namespace ls;
using Catch::Matchers::Contains;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

TEST_CASE("structure estimates bound the bytes the built structures hold", "[budget]") {
  for (const char* scene_name : {"cornell", "generated:20000:7:3"}) {
    const Scene scene = builtin_scene(scene_name);
    for (const char* name : {"bvh", "2l-bvh", "f-ls:3:4", "2l-ls:2:5", "f-ls:6:3"}) {
      const StructureSpec spec = parse_structure(name);
      AccelOptions options;
      options.ls.paper_candidates = true;  // the largest candidates the estimate must cover
      options.ls.min_triangles = 1;
      const Accel accel = build_accel(scene, spec, options);
      const StructureEstimate e = estimate_structure_bytes(scene, spec, options.ls);
      INFO(scene_name << " " << name << ": estimate " << e.total() << ", built " << accel.bytes_total());
      CHECK(e.total() >= accel.bytes_total());
      CHECK(e.ls_bytes >= accel.bytes_ls());
      CHECK(e.ls_nodes_at_most >= accel.ls_nodes.size());
    }
  }
}

TEST_CASE("N = 64 and D = 30 on builtin:instances are refused in well under 2 s", "[budget]") {
  const Scene scene = builtin_scene("instances");
  AccelOptions options;
  options.ls.max_memory = size_t(4) << 30;  // 4 GiB: the same answer on any machine
  for (const char* name : {"f-ls:8:64", "2l-ls:4:64", "f-ls:30:10"}) {
    INFO(name);
    const auto start = std::chrono::steady_clock::now();
    CHECK_THROWS_WITH(build_accel(scene, parse_structure(name), options),
                      Contains("MiB") && Contains("budget of 4096 MiB") && Contains("lower N or D") &&
                          Contains("--max-memory"));
    CHECK(seconds_since(start) < 2.0);
  }
  // The BVH alone counts too: 3.3 million world triangles do not fit in 16 MB.
  options.ls.max_memory = size_t(16) << 20;
  CHECK_THROWS_WITH(build_accel(scene, parse_structure("bvh"), options),
                    Contains("BVH and triangles") && Contains("--max-memory"));
}

TEST_CASE("render buffers over the budget are refused with the size, the estimate and the flags", "[budget]") {
  CHECK(estimate_render_bytes(16384, 16384, 64) > estimate_render_bytes(16384, 16384, 0));
  CHECK(estimate_render_bytes(16384, 16384, 64) >= size_t(16384) * 16384 * 66 * 12);
  CHECK_NOTHROW(check_render_budget(512, 512, 3, size_t(1) << 30));
  CHECK_THROWS_WITH(check_render_budget(16384, 16384, 64, size_t(4) << 30),
                    Contains("16384x16384") && Contains("MiB") && Contains("--size") && Contains("--max-memory"));
  CHECK_THROWS_AS(check_render_budget(16384, 16384, 64, size_t(4) << 30), InputError);
}
