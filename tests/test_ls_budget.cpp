// Per-object Line Space parameters (LsBuildOptions::objects) and 2l-ls:auto (cpu/build/ls_budget.h): each object's
// Line Space equals the one a uniform structure gives it, the budget holds, the pilot's lazily searched
// shafts answer like a full build, and the optimiser keeps its guarantees against brute force.
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/build/ls_budget.h"
#include "cpu/build/structure_budget.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

using namespace ls;

namespace {

const char* kScene = "builtin:generated:12000:6:3";  // six ellipsoids and a light quad, 2 triangles

AccelOptions with_objects(std::vector<ObjectLs> objects) {
  AccelOptions o;
  o.ls.objects = std::move(objects);
  return o;
}

AccelOptions with_budget(double mb, size_t rays = 4096) {
  AccelOptions o;
  o.plan.budget = size_t(mb * 1e6);
  o.plan.rays = rays;
  return o;
}

// The LS node of `accel` at BVH node `node`, or nullptr.
const lsk::LsNode* ls_at(const Accel& accel, uint32_t node) {
  return accel.node_ls[node] == lsk::LS_INVALID ? nullptr : &accel.ls_nodes[accel.node_ls[node]];
}

std::vector<lsk::Hit> trace_all(const Accel& a, const std::vector<lsk::Ray>& rays, Traversal t = Traversal::Reference,
                                const LsLookup& lookup = {}) {
  std::vector<lsk::Hit> hits(rays.size());
  trace_rays(a, lookup, rays.data(), hits.data(), rays.size(), false, nullptr, t);
  return hits;
}

}  // namespace

TEST_CASE("per-object Line Spaces equal those a uniform structure gives each object", "[ls_budget]") {
  const Scene scene = load_scene(kScene);
  REQUIRE(scene.meshes.size() == 7);
  // Object 0 at (2, 4), object 1 at (0, 6), object 3 at (4, 3); the rest none.
  std::vector<ObjectLs> objects(scene.meshes.size());
  objects[0] = {2, 4};
  objects[1] = {0, 6};
  objects[3] = {4, 3};
  const Accel mixed = build_accel(scene, parse_structure("2l-ls:0:1"), with_objects(objects));
  REQUIRE(mixed.ls_info.shafts_per_ls == 0);  // several N: no single shaft count
  size_t shafts = 0;
  for (const lsk::LsNode& ls : mixed.ls_nodes) shafts += lsk::ls_shaft_count(ls.n);
  CHECK(mixed.ls_info.shafts == shafts);

  lsk::TraceContext cm = trace_context(mixed);
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    INFO("mesh " << m);
    const uint32_t root = mixed.object_roots[m];
    const uint32_t end = m + 1 < scene.meshes.size() ? mixed.object_roots[m + 1] : uint32_t(mixed.nodes.size());
    if (objects[m].n == 0) {
      for (uint32_t node = root; node < end; ++node) CHECK(ls_at(mixed, node) == nullptr);
      continue;
    }
    const std::string name = "2l-ls:" + std::to_string(objects[m].depth) + ":" + std::to_string(objects[m].n);
    const Accel uniform = build_accel(scene, parse_structure(name));
    lsk::TraceContext cu = trace_context(uniform);
    size_t compared = 0;
    for (uint32_t node = root; node < end; ++node) {
      const lsk::LsNode* a = ls_at(mixed, node);
      const lsk::LsNode* b = ls_at(uniform, node);
      REQUIRE((a == nullptr) == (b == nullptr));
      if (!a) continue;
      lsk::LsNode a0 = *a, b0 = *b;
      a0.candidates = b0.candidates = 0;  // offsets differ: the arrays hold other objects too
      CHECK(std::memcmp(&a0, &b0, sizeof(a0)) == 0);
      for (uint32_t s = 0; s < lsk::ls_shaft_count(a->n); ++s) {
        REQUIRE(cm.ls_candidate(*a, s) == cu.ls_candidate(*b, s));
        ++compared;
      }
    }
    CHECK(compared > 0);
  }
}

TEST_CASE("per-object Line Spaces with refusal angle 0 give the exact structure's hits", "[ls_budget]") {
  const Scene scene = load_scene(kScene);
  std::vector<ObjectLs> objects(scene.meshes.size(), ObjectLs{2, 3});
  objects[2] = {0, 5};
  objects[4] = {};
  const Accel exact = build_accel(scene, parse_structure("2l-bvh"));
  const Accel mixed = build_accel(scene, parse_structure("2l-ls:0:1"), with_objects(objects));
  LsLookup refuse_all;
  refuse_all.angle_degrees = 0.0f;
  const std::vector<lsk::Ray> rays = generate_rays(scene, exact, RayKind::Diffuse, 20000, 5);
  for (Traversal t : {Traversal::Reference, Traversal::Fast}) {
    const std::vector<lsk::Hit> a = trace_all(exact, rays, t), b = trace_all(mixed, rays, t, refuse_all);
    REQUIRE(std::memcmp(a.data(), b.data(), a.size() * sizeof(lsk::Hit)) == 0);
  }
}

TEST_CASE("2l-ls:auto stays within its budget and takes exactly the bytes it predicts", "[ls_budget]") {
  const Scene scene = load_scene(kScene);
  const Accel exact = build_accel(scene, parse_structure("2l-bvh"));
  const size_t fixed = exact.nodes.size() * 4 + exact.tris.size() * sizeof(lsk::LsRecord);
  for (double extra_mb : {0.0, 0.02, 0.3, 3.0}) {
    const double mb = double(fixed) / 1e6 + extra_mb;
    INFO("budget " << mb << " MB");
    const Accel a = build_planned_accel(scene, parse_structure("2l-ls:auto"), with_budget(mb));
    REQUIRE(a.ls_plan);
    CHECK(a.ls_plan->fixed_bytes == fixed);
    CHECK(a.bytes_ls() == a.ls_plan->predicted_bytes);
    CHECK(a.bytes_ls() <= size_t(mb * 1e6));
    CHECK(a.ls_plan->plan.bytes_ls == a.bytes_ls());
    // Every object of the plan got the D and N the plan names.
    for (const LsPlanRow& r : a.ls_plan->rows) {
      CHECK(a.ls_options.objects[r.mesh] == r.chosen);
      CHECK((r.reason == "chosen") == (r.chosen.n > 0));
    }
    // The light quad (2 triangles) can hold no Line Space of at least min_triangles.
    CHECK(a.ls_plan->rows.back().reason == "too small");
  }
}

TEST_CASE("2l-ls:auto is refused without a budget, below its fixed part, and over --max-memory", "[ls_budget]") {
  const Scene scene = load_scene(kScene);
  CHECK_THROWS_WITH(build_planned_accel(scene, parse_structure("2l-ls:auto")), Catch::Contains("needs a Line Space budget"));
  // build_accel itself never plans: without a plan it refuses, whatever the budget.
  CHECK_THROWS_WITH(build_accel(scene, parse_structure("2l-ls:auto"), with_budget(1.0)), Catch::Contains("needs its plan"));
  CHECK_THROWS_WITH(build_planned_accel(scene, parse_structure("2l-ls:auto"), with_budget(0.01)),
                    Catch::Contains("raise --ls-budget"));
  AccelOptions small = with_budget(500.0);
  small.limits.max_memory = 100000000;  // 100 MB: the 500 MB budget itself is over it
  CHECK_THROWS_WITH(build_planned_accel(scene, parse_structure("2l-ls:auto"), small), Catch::Contains("--ls-budget"));
  CHECK(parse_structure("2l-ls:auto").name() == "2l-ls:auto");
  CHECK(parse_structure("2L-LS:AUTO").budgeted);
  CHECK_THROWS_AS(parse_structure("f-ls:auto"), InputError);
}

TEST_CASE("2l-ls:auto's estimate is the menu's largest plan where the budget is larger", "[ls_budget]") {
  // A budget far over what any plan can spend is no reason to refuse the structure: the estimate is
  // the smaller of the budget and every object at the menu's largest D and N.
  const Scene scene = load_scene(kScene);
  const StructureSpec spec = parse_structure("2l-ls:auto");
  AccelOptions huge = with_budget(1e6);  // 1 TB
  AccelOptions largest;
  largest.ls.objects.assign(scene.meshes.size(), ObjectLs{8, 10});
  const StructureEstimate bound = estimate_structure_bytes(scene, parse_structure("2l-ls:8:10"), largest);
  const StructureEstimate e = estimate_structure_bytes(scene, spec, huge);
  CHECK(e.ls_bytes == bound.ls_bytes);
  CHECK(e.ls_bytes < huge.plan.budget);
  huge.limits.max_memory = 2 * bound.total();
  CHECK_NOTHROW(check_structure_budget(scene, spec, huge));
  huge.limits.max_memory = bound.total() - 1;
  CHECK_THROWS_WITH(check_structure_budget(scene, spec, huge), Catch::Contains("lower --ls-budget"));
  // A budget under the largest plan is itself the estimate.
  const AccelOptions small = with_budget(double(bound.ls_bytes) / 2e6);
  CHECK(estimate_structure_bytes(scene, spec, small).ls_bytes == small.plan.budget);
}

TEST_CASE("the pilot's lazily searched shafts answer like fully built Line Spaces", "[ls_budget]") {
  // The plan's joint pilot figures come from Line Spaces whose only searched shafts are those the
  // pilot's rays can look up.  A full build of the same structure must give the same answers.
  const Scene scene = load_scene(kScene);
  const Accel exact = build_accel(scene, parse_structure("2l-bvh"));
  const size_t fixed = exact.nodes.size() * 4 + exact.tris.size() * sizeof(lsk::LsRecord);
  AccelOptions options = with_budget(double(fixed) / 1e6 + 0.8, 6000);
  // Wide enough that some pilot answers are wrong on this small scene; from the ellipsoids' surfaces
  // exact mode answers only empty shafts, and saves the pilot no work, so the plan would keep none.
  options.plan.lookup.angle_degrees = 60.0f;
  options.plan.lookup.behind = LsBehind::Empty;
  const LsLookup lookup = options.plan.lookup;
  const Accel planned = build_planned_accel(scene, parse_structure("2l-ls:auto"), options);
  const LsPlan& plan = *planned.ls_plan;
  REQUIRE(!plan.reference.empty());
  const LsPilot pilot = ls_budget_pilot(scene, exact, options.plan.rays);
  REQUIRE(pilot.rays.size() == plan.pilot_rays);
  REQUIRE(pilot.shadow_rays.size() == plan.pilot_shadow_rays);
  REQUIRE(plan.pilot_shadow_rays > 0);  // the generated scene has a light quad
  const double tolerance = pilot_tolerance(scene);
  auto wrong_rays = [&](const Accel& a) {
    long wrong = 0;
    for (bool any_hit : {false, true}) {
      const std::vector<lsk::Ray>& rays = any_hit ? pilot.shadow_rays : pilot.rays;
      std::vector<lsk::Hit> truth(rays.size()), got(rays.size());
      trace_rays(exact, lookup, rays.data(), truth.data(), rays.size(), any_hit, nullptr, Traversal::Reference);
      trace_rays(a, lookup, rays.data(), got.data(), rays.size(), any_hit, nullptr, Traversal::Reference);
      for (size_t i = 0; i < rays.size(); ++i) wrong += pilot_answer_wrong(rays[i], got[i], truth[i], any_hit, tolerance);
    }
    return wrong;
  };
  const double n = double(pilot.rays.size() + pilot.shadow_rays.size());
  CHECK(wrong_rays(planned) == std::lround(plan.plan.error * n));
  const Accel uniform = build_accel(scene, parse_structure(plan.reference));
  CHECK(wrong_rays(uniform) == std::lround(plan.uniform.error * n));
  CHECK(uniform.bytes_ls() == plan.uniform.bytes_ls);
  CHECK(plan.plan.error > 0.0);  // the approximation was exercised
}

TEST_CASE("2l-ls:auto is deterministic", "[ls_budget]") {
  const Scene scene = load_scene(kScene);
  const Accel exact = build_accel(scene, parse_structure("2l-bvh"));
  const double mb = double(exact.nodes.size() * 4 + exact.tris.size() * sizeof(lsk::LsRecord)) / 1e6 + 0.5;
  const Accel a = build_planned_accel(scene, parse_structure("2l-ls:auto"), with_budget(mb));
  const Accel b = build_planned_accel(scene, parse_structure("2l-ls:auto"), with_budget(mb));
  CHECK(a.ls_options.objects == b.ls_options.objects);
  CHECK(a.ls_candidates == b.ls_candidates);
}

TEST_CASE("the plan optimiser keeps its guarantees, checked against brute force", "[ls_budget]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int optimal = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const size_t objects = 1 + rng() % 4;
    std::vector<std::vector<PlanOption>> options(objects);
    for (auto& opts : options) {
      opts.push_back(PlanOption{});  // none
      const size_t k = 1 + rng() % 4;
      for (size_t i = 0; i < k; ++i)
        opts.push_back(PlanOption{ObjectLs{int(i), 2}, 1 + rng() % 100, 0.1 * u(rng), 2.0 * u(rng) - 0.5});
    }
    std::vector<size_t> reference(objects);
    size_t ref_bytes = 0;
    double ref_error = 0.0, ref_saved = 0.0;
    for (size_t o = 0; o < objects; ++o) {
      reference[o] = rng() % options[o].size();
      ref_bytes += options[o][reference[o]].bytes;
      ref_error += options[o][reference[o]].error;
      ref_saved += options[o][reference[o]].saved;
    }
    const size_t room = ref_bytes + rng() % 50;
    const PlanChoice c = optimise_plan(options, room, reference);
    size_t bytes = 0;
    double error = 0.0, saved = 0.0;
    for (size_t o = 0; o < objects; ++o) {
      bytes += options[o][c.choice[o]].bytes;
      error += options[o][c.choice[o]].error;
      saved += options[o][c.choice[o]].saved;
    }
    INFO("trial " << trial);
    CHECK(bytes <= room);
    CHECK(saved >= ref_saved - 1e-12);
    CHECK(error <= ref_error + 1e-12);
    // Brute force over every combination: the true optimum under the same constraints.
    double optimum = std::numeric_limits<double>::infinity();
    std::vector<size_t> pick(objects, 0);
    while (true) {
      size_t b = 0;
      double e = 0.0, sv = 0.0;
      for (size_t o = 0; o < objects; ++o) b += options[o][pick[o]].bytes, e += options[o][pick[o]].error, sv += options[o][pick[o]].saved;
      if (b <= room && sv >= ref_saved - 1e-12) optimum = std::min(optimum, e);
      size_t o = 0;
      while (o < objects && ++pick[o] == options[o].size()) pick[o++] = 0;
      if (o == objects) break;
    }
    CHECK(error >= optimum - 1e-12);  // nothing beats the optimum (the brute force is right)
    if (error <= optimum + 1e-12) ++optimal;
  }
  // The Lagrangian greedy is not exact, but it must find the optimum in most small cases.
  INFO("optimum found in " << optimal << " of 300 trials");
  CHECK(optimal >= 270);
  // No reference: no Line Space at all.
  const PlanChoice none = optimise_plan({{PlanOption{}, PlanOption{ObjectLs{0, 2}, 10, 0.1, 5.0}}}, 100, {});
  CHECK(none.choice == std::vector<size_t>{0});
}
