// Memory budgets: the estimates are upper bounds of what the structures really take, and over-budget
// structures and renders are refused from the parameters alone (fast, before allocating).
#include "common/base/memory_budget.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/build/structure_budget.h"
#include "cpu/trace/fast_path_budget.h"
#include "scenes/load_scene.h"

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
      const StructureEstimate e = estimate_structure_bytes(scene, spec, options);
      INFO(scene_name << " " << name << ": estimate " << e.total() << ", built " << accel.bytes_total());
      CHECK(e.total() >= accel.bytes_total());
      CHECK(e.ls_bytes >= accel.bytes_ls());
      CHECK(e.ls_nodes_at_most >= accel.ls_nodes.size());
    }
  }
}

TEST_CASE("the fast path's bound covers its wide trees and blocks, and a structure without room for it is refused", "[budget]") {
  // Both widths, flat and two-level, exact and Line Space, on a scene of unique meshes and
  // on an instanced one.
  for (const char* scene_name : {"cornell", "generated:20000:7:3", "instances"}) {
    const Scene scene = builtin_scene(scene_name);
    for (const char* name : {"bvh", "2l-bvh", "f-ls:3:4", "2l-ls:2:3"}) {
      if (std::string(scene_name) == "instances" && !parse_structure(name).two_level()) continue;  // 3.3 million world triangles
      for (int exact_width : {4, 8}) {
        AccelOptions options;
        options.exact_width = exact_width;
        options.search_candidates = false;
        const Accel accel = build_accel(scene, parse_structure(name), options);
        const size_t bound = fast_path_bytes_at_most(accel, exact_width);
        INFO(scene_name << " " << name << " width " << exact_width << ": bound " << bound << ", built " << accel.bytes_wide());
        CHECK(accel.bytes_wide() > 0);
        CHECK(bound >= accel.bytes_wide());
        CHECK(bound <= 4 * accel.bytes_wide());  // a bound, not a refusal of everything
      }
    }
  }
  // f-ls:3:4 on cornell: its parameter estimate (the BVH's build, the Line Space) fits a budget of
  // exactly that estimate, the structure and its fast path's bound together do not.
  const Scene scene = builtin_scene("cornell");
  const StructureSpec spec = parse_structure("f-ls:3:4");
  AccelOptions options;
  options.ls.paper_candidates = true;
  options.ls.min_triangles = 1;
  options.search_candidates = false;
  const Accel fits = build_accel(scene, spec, options);
  const size_t whole = fits.bytes_total() + fast_path_bytes_at_most(fits, options.exact_width);
  options.limits.max_memory = estimate_structure_bytes(scene, spec, options).total();
  INFO("estimate " << options.limits.max_memory << ", structure and fast path's bound " << whole);
  REQUIRE(options.limits.max_memory < whole);
  CHECK_THROWS_WITH(build_accel(scene, spec, options),
                    Contains("fast path") && Contains("triangle blocks") && Contains("over the budget") &&
                        Contains("--max-memory"));
  // The amount compared with the budget is named, so it reads larger than the budget (the fast path
  // alone can read smaller: "4.7 MiB beside the structure's 1.7 MiB, over the budget of 4.7 MiB").
  CHECK_THROWS_WITH(build_accel(scene, spec, options),
                    Contains("together " + mib_text(double(whole)) + ", over the budget of " +
                             mib_budget_text(double(options.limits.max_memory))));
  options.limits.max_memory = whole;
  CHECK_NOTHROW(build_accel(scene, spec, options));
}

TEST_CASE("N = 64 and D = 30 on builtin:instances are refused in well under 2 s", "[budget]") {
  const Scene scene = builtin_scene("instances");
  AccelOptions options;
  options.limits.max_memory = size_t(4) << 30;  // 4 GiB: the same answer on any machine
  for (const char* name : {"f-ls:8:64", "2l-ls:4:64", "f-ls:30:10"}) {
    INFO(name);
    const auto start = std::chrono::steady_clock::now();
    CHECK_THROWS_WITH(build_accel(scene, parse_structure(name), options),
                      Contains("MiB") && Contains("budget of 4096 MiB") && Contains("lower N or D") &&
                          Contains("--max-memory"));
    CHECK(seconds_since(start) < 2.0);
  }
  // The BVH alone counts too: 3.3 million world triangles do not fit in 16 MB.
  options.limits.max_memory = size_t(16) << 20;
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

TEST_CASE("the Line Space layout re-checks the budget with its actual LS nodes, and names both in MiB", "[budget]") {
  // build_accel's estimate is an upper bound made before the BVH exists; the layout checks again with
  // the LS nodes it placed.  Called here directly with a budget the first check never saw.
  const Scene scene = load_scene("builtin:cornell");
  Accel accel = build_accel(scene, parse_structure("f-ls:3:8"));
  REQUIRE(accel.ls_info.ls_nodes > 0);
  Limits tight;
  tight.max_memory = 1000000;  // 1 MB = 0.95 MiB: a budget is named rounded down, in tenths, "0.9 MiB"
  CHECK_THROWS_WITH(layout_line_space(scene, accel.ls_options, tight, accel),
                    Contains("structure 'f-ls:3:8': its Line Space would take about") &&
                        Contains(std::to_string(accel.ls_info.ls_nodes) + " LS nodes x") && Contains("over the budget of 0.9 MiB") &&
                        Contains("lower N or D, or raise --max-memory"));
}

TEST_CASE("amounts are named rounded up and budgets rounded down, so an amount over a budget reads larger", "[budget]") {
  constexpr double mib = double(1 << 20);
  CHECK(mib_text(0.0) == "0 MiB");
  CHECK(mib_budget_text(0.0) == "0 MiB");
  CHECK(mib_text(mib) == "1 MiB");  // exact values stay as they are, in both
  CHECK(mib_budget_text(mib) == "1 MiB");
  CHECK(mib_text(1e6) == "1 MiB");  // 0.954 MiB
  CHECK(mib_budget_text(1e6) == "0.9 MiB");
  CHECK(mib_text(4.5e6) == "4.3 MiB");  // 4.29 MiB
  CHECK(mib_budget_text(4.5e6) == "4.2 MiB");
  CHECK(mib_text(9.99 * mib) == "10 MiB");  // tenths end at 10 MiB
  CHECK(mib_budget_text(9.99 * mib) == "9.9 MiB");
  CHECK(mib_budget_text(10.0 * mib) == "10 MiB");
  CHECK(mib_text(4e9) == "3815 MiB");
  CHECK(mib_budget_text(4e9) == "3814 MiB");
  // The refusals' property: whenever an amount exceeds a budget, its text's number is the larger.
  // Rounding both up failed it ("5 MiB ... over the budget of 5 MiB" at --max-memory 4.5 on 5.1 MB).
  auto number = [](const std::string& text) { return std::stod(text.substr(0, text.find(' '))); };
  for (double budget = 0.05 * mib; budget < 300.0 * mib; budget *= 1.37)
    for (double over : {1.0, 1.001, 1.01, 1.1, 1.5}) {
      const double amount = budget * over + 1.0;
      INFO(budget << " " << amount);
      CHECK(number(mib_text(amount)) > number(mib_budget_text(budget)));
    }
}

TEST_CASE("rays held over the budget are refused, at the budget they are not", "[budget]") {
  // Held: the rays and their hits; made here, at least the generator's two ray arrays and flags.
  CHECK(ray_bytes(1000, false, 1) == 1000 * (sizeof(lsk::Ray) + sizeof(lsk::Hit)));
  CHECK(ray_bytes(1000, false, 0) == 1000 * sizeof(lsk::Ray));
  CHECK(ray_bytes(1000, true, 0) == 1000 * (2 * sizeof(lsk::Ray) + 1));
  CHECK(ray_bytes(1000, true, 1) == 1000 * (2 * sizeof(lsk::Ray) + 1));
  CHECK(ray_bytes(1000, true, 2) == 1000 * (sizeof(lsk::Ray) + 2 * sizeof(lsk::Hit)));
  CHECK_NOTHROW(check_held_budget("test's rays", 1000000, 1000000, "fewer"));
  CHECK_THROWS_WITH(check_held_budget("test's rays", 1000001, 1000000, "use fewer"),
                    Contains("test's rays take up to 1 MiB, over the budget of 0.9 MiB: use fewer"));
}
