// The fast CPU path (cpu/trace/fast_tracer.h: wide SIMD BVH, four-lane triangle filter) against the scalar
// reference kernels: every hit record bit for bit (t, u, v, ids), for closest and any hit, on the
// built-in scenes and random ones, every structure, both widths of the order-free tree; and the
// reference walking the farther child first against its own nearest-first walk: the Line Space's
// answers do not depend on the visiting order.
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/trace/exact_wide_bvh.h"
#include "cpu/trace/fast_tracer.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/reference_trace.h"
#include "cpu/trace/trace_rays.h"
#include "cpu/trace/triangle_blocks.h"
#include "scenes/load_scene.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>

// StdRng: the standard distributions.  Meshes carry face normals as vertex normals (the Line Space
// extrapolates them).
using namespace test_support;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::string describe(const lsk::Hit& h) {
  std::ostringstream s;
  s.precision(9);
  s << "t=" << h.t << " inst=" << h.instance << " tri=" << h.triangle << " u=" << h.u << " v=" << h.v;
  return s.str();
}

std::string describe(const lsk::LsCounters& c) {
  std::ostringstream s;
  s << c.lookups << " lookups, " << c.empty << " empty, " << c.accepted << " accepted, refused angle " << c.refused_angle
    << " behind " << c.refused_behind << " beyond " << c.refused_beyond << " parallel " << c.refused_parallel
    << " no shaft " << c.refused_no_shaft;
  return s.str();
}

// The reference kernel with the farther child visited first (TraceContext::walk_far_first).
std::vector<lsk::Hit> trace_far_first(const ls::Accel& accel, const ls::LsLookup& lookup, const std::vector<lsk::Ray>& rays,
                                      bool any_hit) {
  lsk::TraceContext c = ls::trace_context(accel, lookup);
  c.walk_far_first = 1u;
  std::vector<lsk::Hit> hits(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) hits[i] = ls::trace_ray_reference(c, rays[i], accel.spec.two_level(), any_hit);
  return hits;
}

// Runs both paths on the same rays and requires identical hit records (any hit: both run the
// reference kernel, so the Line Space counters too), and the reference's farthest-first walk the
// same closest hits (any hit: the same rays hit); returns the number of Line Space lookups.
size_t require_same(const ls::Accel& accel, const std::vector<lsk::Ray>& rays, bool any_hit, const std::string& what,
                    const ls::LsLookup& lookup = {}) {
  INFO(what << ", " << accel.spec.name() << ", " << accel.fast->exact_width() << "-wide order-free tree, "
            << (any_hit ? "any hit" : "closest hit"));
  std::vector<lsk::Hit> ref(rays.size()), fast(rays.size());
  lsk::LsCounters ref_counters{}, fast_counters{};
  ls::trace_rays(accel, lookup, rays.data(), ref.data(), rays.size(), any_hit, &ref_counters, ls::Traversal::Reference);
  ls::trace_rays(accel, lookup, rays.data(), fast.data(), rays.size(), any_hit, &fast_counters, ls::Traversal::Fast);
  size_t mismatches = 0, hits = 0;
  std::string first;
  for (size_t i = 0; i < rays.size(); ++i) {
    hits += ref[i].triangle != lsk::LS_INVALID;
    if (std::memcmp(&ref[i], &fast[i], sizeof(lsk::Hit)) != 0) {
      if (mismatches++ == 0) first = "ray " + std::to_string(i) + ": reference " + describe(ref[i]) + ", fast " + describe(fast[i]);
    }
  }
  INFO("first mismatch: " << first);
  CHECK(mismatches == 0);
  CHECK(hits > 0);  // the ray set exercises something
  if (accel.spec.line_space() && any_hit) {
    INFO("reference counters: " << describe(ref_counters) << "\nfast counters:      " << describe(fast_counters));
    CHECK(std::memcmp(&ref_counters, &fast_counters, sizeof(lsk::LsCounters)) == 0);
  }
  const std::vector<lsk::Hit> far = trace_far_first(accel, lookup, rays, any_hit);
  size_t order_mismatches = 0;
  std::string first_order;
  for (size_t i = 0; i < rays.size(); ++i) {
    const bool same = any_hit ? (far[i].triangle == lsk::LS_INVALID) == (ref[i].triangle == lsk::LS_INVALID)
                              : std::memcmp(&ref[i], &far[i], sizeof(lsk::Hit)) == 0;
    if (!same && order_mismatches++ == 0)
      first_order = "ray " + std::to_string(i) + ": nearest first " + describe(ref[i]) + ", farthest first " + describe(far[i]);
  }
  INFO("first mismatch between the walk orders: " << first_order);
  CHECK(order_mismatches == 0);
  return ref_counters.lookups;
}

// width: the order-free tree's.
ls::AccelOptions options(int width, uint32_t min_triangles = 0) {
  ls::AccelOptions o;
  o.exact_width = width;
  o.ls.min_triangles = min_triangles;
  return o;
}

void check_scene(const ls::Scene& scene, const std::string& name, const std::vector<std::string>& structures, size_t count,
                 const std::vector<int>& widths = {4, 8}, const char* exact_name = "bvh") {
  const ls::Accel exact = ls::build_accel(scene, ls::parse_structure(exact_name));
  std::vector<std::pair<std::string, std::vector<lsk::Ray>>> sets;
  for (const char* kind : {"primary", "diffuse", "random", "shadow"})
    sets.push_back({kind, ls::generate_rays(scene, exact, ls::parse_ray_kind(kind), count, 11)});
  for (int width : widths)
    for (const std::string& s : structures) {
      const ls::Accel accel = ls::build_accel(scene, ls::parse_structure(s), options(width));
      REQUIRE(accel.fast);
      REQUIRE(accel.fast->exact_width() == width);
      size_t lookups = 0;
      for (const auto& [kind, rays] : sets) {
        lookups += require_same(accel, rays, kind == "shadow", name + ", " + kind + " rays");
        if (kind != "shadow") lookups += require_same(accel, rays, true, name + ", " + kind + " rays");
      }
      INFO(name << ", " << s);
      if (accel.spec.line_space() && accel.ls_info.ls_nodes > 0) CHECK(lookups > 0);  // the Line Space was exercised
    }
}

ls::Scene random_scene(uint32_t seed) {
  StdRng rng(seed);
  ls::Scene s;
  s.name = "random";
  s.materials.push_back(ls::Material{});
  s.meshes.push_back(with_face_normals(scattered_soup(rng, 2000, 1.0f, 0.15f)));
  s.meshes.push_back(with_face_normals(square_grid(16, 0.0f, 1.0f)));
  s.meshes.push_back(with_face_normals(scattered_soup(rng, 40, 0.5f, 0.3f)));
  for (uint32_t i = 0; i < 12; ++i) {
    ls::Instance inst;
    inst.mesh = i % 3;
    glm::mat4 m = glm::translate(glm::mat4(1.0f), rng.vec(-3.0f, 3.0f));
    if (i % 4 != 0) m = glm::rotate(m, rng.range(0.0f, 6.28f), glm::normalize(rng.vec(-1.0f, 1.0f) + glm::vec3(0.01f)));
    glm::vec3 scale = rng.vec(0.5f, 1.5f);
    if (i % 3 == 1) scale.x = -scale.x;
    inst.object_to_world = glm::scale(m, scale);
    s.instances.push_back(inst);
  }
  s.camera.position = glm::vec3(0.0f, 1.0f, 9.0f);
  s.camera.target = glm::vec3(0.0f);
  ls::validate_scene(s);
  return s;
}

}  // namespace

TEST_CASE("wide BVH: same hits as the reference, in either walk order, on builtin:cornell", "[wide]") {
  check_scene(ls::load_scene("builtin:cornell"), "builtin:cornell", {"bvh", "2l-bvh", "f-ls:4:4", "f-ls:8:6", "2l-ls:2:4", "2l-ls:0:6"}, 4000);
}

TEST_CASE("wide BVH: same hits as the reference, in either walk order, on builtin:generated", "[wide]") {
  check_scene(ls::load_scene("builtin:generated:30000:12:5"), "builtin:generated:30000:12:5",
              {"bvh", "2l-bvh", "f-ls:8:4", "2l-ls:4:4"}, 3000);
}

TEST_CASE("wide BVH: same hits as the reference, in either walk order, on builtin:instances", "[wide]") {
  // Two-level only: the flat BVH over its 3.3 M world triangles would take most of a minute here.
  check_scene(ls::load_scene("builtin:instances"), "builtin:instances", {"2l-bvh", "2l-ls:4:3"}, 2000, {4}, "2l-bvh");
}

TEST_CASE("wide BVH: same hits as the reference, in either walk order, on random instanced scenes", "[wide]") {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const ls::Scene scene = random_scene(seed);
    check_scene(scene, "random scene " + std::to_string(seed), {"bvh", "2l-bvh", "f-ls:3:3", "f-ls:6:4", "2l-ls:2:3", "2l-ls:0:4"},
                2000);
  }
}

TEST_CASE("wide BVH: same answers at refusal angles 0 and 89 degrees and with small subtrees skipped", "[wide]") {
  const ls::Scene scene = random_scene(7);
  const ls::Accel exact = ls::build_accel(scene, ls::parse_structure("bvh"));
  const std::vector<lsk::Ray> rays = ls::generate_rays(scene, exact, ls::RayKind::Diffuse, 3000, 5);
  for (float angle : {0.0f, 89.0f})
    for (uint32_t min_tris : {0u, 8u})
      for (const char* s : {"f-ls:5:4", "2l-ls:3:4"}) {
        const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(4, min_tris));
        ls::LsLookup lookup;
        lookup.angle_degrees = angle;
        CHECK(require_same(a, rays, false, "angle " + std::to_string(angle) + ", min triangles " + std::to_string(min_tris), lookup) > 0);
      }
}

TEST_CASE("wide BVH: same answers with --ls-behind reverse and empty, in either walk order", "[wide]") {
  for (const char* scene_name : {"builtin:cornell", "builtin:generated:30000:12:5"}) {
    const ls::Scene scene = ls::load_scene(scene_name);
    const ls::Accel exact = ls::build_accel(scene, ls::parse_structure("bvh"));
    std::vector<std::pair<const char*, std::vector<lsk::Ray>>> sets;
    for (const char* kind : {"diffuse", "random", "shadow"})
      sets.push_back({kind, ls::generate_rays(scene, exact, ls::parse_ray_kind(kind), 3000, 9)});
    // Each structure is built once and traced with every ray set: the builds, not the walks, are
    // what the sanitizer builds spend their time on.
    for (int width : {4, 8})
      for (const char* s : {"f-ls:4:4", "f-ls:8:6", "2l-ls:2:4", "2l-ls:0:6"}) {
        const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(width));
        for (const auto& [kind, rays] : sets)
          for (ls::LsBehind behind : {ls::LsBehind::Reverse, ls::LsBehind::Empty}) {
            // empty differs from reverse in one line of the shared lookup: one width, one flat and one
            // two-level structure (the sanitizer builds run this test too).
            if (behind == ls::LsBehind::Empty && (width != 8 || (std::string(s) != "f-ls:8:6" && std::string(s) != "2l-ls:2:4")))
              continue;
            ls::LsLookup lookup;
            lookup.behind = behind;
            const std::string what = std::string(scene_name) + ", " + kind + " rays, " + ls::ls_behind_name(behind);
            CHECK(require_same(a, rays, false, what, lookup) > 0);
            CHECK(require_same(a, rays, true, what, lookup) > 0);
          }
      }
  }
}

TEST_CASE("wide BVH: rays traced in flight get the hits and counters each gets alone", "[wide]") {
  // A Line Space structure walks several rays in turn, parking each at its lookups; every ray must
  // end as it does when it is the only one in the call, counters included.
  std::map<std::string, size_t> accepted;  // per structure: lookups that answered (parked and landed)
  for (const char* scene_name : {"builtin:cornell", "builtin:generated:30000:12:5", "random"}) {
    const ls::Scene scene = std::string(scene_name) == "random" ? random_scene(6) : ls::load_scene(scene_name);
    const ls::Accel exact = ls::build_accel(scene, ls::parse_structure("bvh"));
    std::vector<std::pair<const char*, std::vector<lsk::Ray>>> sets;
    for (const char* kind : {"diffuse", "random", "shadow"})
      sets.push_back({kind, ls::generate_rays(scene, exact, ls::parse_ray_kind(kind), 1000, 13)});
    for (const char* s : {"f-ls:0:4", "f-ls:4:4", "f-ls:8:6", "2l-ls:2:4", "2l-ls:0:6"}) {
      const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(8));
      for (const auto& [kind, rays] : sets)
        for (ls::LsBehind behind : {ls::LsBehind::Exact, ls::LsBehind::Empty, ls::LsBehind::Reverse})
          for (bool occlusion : {false, true}) {
            ls::LsLookup lookup;
            lookup.behind = behind;
            INFO(scene_name << ", " << kind << " rays, " << s << ", " << ls::ls_behind_name(behind) << (occlusion ? ", occlusion" : ""));
            auto trace = [&](lsk::TraceContext& c, const lsk::Ray* r, lsk::Hit* h, size_t n) {
              if (occlusion)
                a.fast->occluded(c, r, h, n);
              else
                a.fast->trace(c, r, h, n, false);
            };
            std::vector<lsk::Hit> together(rays.size()), alone(rays.size());
            lsk::TraceContext c_together = ls::trace_context(a, lookup);
            trace(c_together, rays.data(), together.data(), rays.size());
            lsk::TraceContext c_alone = ls::trace_context(a, lookup);
            for (size_t i = 0; i < rays.size(); ++i) trace(c_alone, &rays[i], &alone[i], 1);
            size_t mismatches = 0, hits = 0;
            for (size_t i = 0; i < rays.size(); ++i) {
              mismatches += std::memcmp(&together[i], &alone[i], sizeof(lsk::Hit)) != 0;
              hits += alone[i].triangle != lsk::LS_INVALID;
            }
            CHECK(mismatches == 0);
            CHECK(hits > 0);
            INFO("together: " << describe(c_together.ls_counters) << "\nalone:    " << describe(c_alone.ls_counters));
            CHECK(c_alone.ls_counters.lookups > 0);
            accepted[s] += c_alone.ls_counters.accepted;
            CHECK(std::memcmp(&c_together.ls_counters, &c_alone.ls_counters, sizeof(lsk::LsCounters)) == 0);
          }
    }
  }
  for (const auto& [structure, count] : accepted) {
    INFO(structure);
    CHECK(count > 0);
  }
}

TEST_CASE("wide BVH: --skip leaves out the lookups, or the walks of refused subtrees, and nothing else", "[wide]") {
  // Without lookups every Line Space lane answers "empty": the closest hit is the closest of the
  // triangles outside every Line Space node's range, found here by brute force.  At refusal angle 0
  // every lookup refuses, so leaving out the refused walks must answer the same.
  size_t outside_hits = 0;  // hits outside the Line Space nodes: the brute force is not empty
  for (const char* scene_name : {"builtin:cornell", "random"}) {
    const ls::Scene scene = std::string(scene_name) == "random" ? random_scene(6) : ls::load_scene(scene_name);
    const ls::Accel exact = ls::build_accel(scene, ls::parse_structure("bvh"));
    std::vector<lsk::Ray> rays = ls::generate_rays(scene, exact, ls::RayKind::Diffuse, 1000, 17);
    const std::vector<lsk::Ray> random = ls::generate_rays(scene, exact, ls::RayKind::Random, 1000, 17);
    rays.insert(rays.end(), random.begin(), random.end());
    for (const char* s : {"f-ls:0:4", "f-ls:4:4", "f-ls:8:6"}) {
      // Subtrees of fewer than 8 triangles get no Line Space: hits outside them too.
      const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(8, 8));
      std::vector<bool> under_ls(a.tris.size(), false);
      for (const lsk::LsNode& node : a.ls_nodes)
        for (uint32_t i = node.range_first; i < node.range_first + node.range_count; ++i) under_ls[i] = true;
      std::vector<lsk::Hit> outside(rays.size());
      for (size_t r = 0; r < rays.size(); ++r) {
        const lsk::Ray& ray = rays[r];
        const lsk::TriRay tri_ray = lsk::make_tri_ray(ray.origin, ray.dir);
        lsk::Hit hit = lsk::empty_hit(ray);
        for (size_t i = 0; i < a.tris.size(); ++i) {
          float t, u, v;
          const lsk::Triangle& tri = a.tris[i];
          if (!under_ls[i] && lsk::ray_triangle(tri_ray, ray.tmin, hit.t, glm::vec3(tri.v0), glm::vec3(tri.v1), glm::vec3(tri.v2), t, u, v))
            lsk::offer_hit(t, u, v, a.tri_instances[i], a.tri_ids[i], hit);
        }
        outside[r] = lsk::finish_hit(hit);
      }
      std::vector<lsk::Hit> full(rays.size());
      ls::trace_rays(a, {}, rays.data(), full.data(), rays.size(), false, nullptr, ls::Traversal::Fast);
      size_t changed = 0;  // rays whose full answer comes from a Line Space node: the skip must show
      for (size_t r = 0; r < rays.size(); ++r) changed += std::memcmp(&full[r], &outside[r], sizeof(lsk::Hit)) != 0;
      INFO(scene_name << ", " << s << ": " << changed << " rays answered from Line Space nodes");
      CHECK(changed > 0);
      for (const auto& [skip, angle] : {std::pair{ls::LsSkip::Lookups, 45.0f}, std::pair{ls::LsSkip::Lookups, 0.0f},
                                        std::pair{ls::LsSkip::RefusedWalks, 0.0f}}) {
        ls::LsLookup lookup;
        lookup.skip = skip;
        lookup.angle_degrees = angle;
        INFO((skip == ls::LsSkip::Lookups ? "without lookups" : "without refused walks") << ", angle " << angle);
        std::vector<lsk::Hit> hits(rays.size()), blocked(rays.size());
        lsk::LsCounters counters{};
        ls::trace_rays(a, lookup, rays.data(), hits.data(), rays.size(), false, &counters, ls::Traversal::Fast);
        ls::trace_occlusion(a, lookup, rays.data(), blocked.data(), rays.size(), nullptr, ls::Traversal::Fast);
        size_t mismatches = 0, wrong_occlusion = 0, hit_count = 0;
        for (size_t r = 0; r < rays.size(); ++r) {
          mismatches += std::memcmp(&hits[r], &outside[r], sizeof(lsk::Hit)) != 0;
          wrong_occlusion += (blocked[r].triangle != lsk::LS_INVALID) != (outside[r].triangle != lsk::LS_INVALID);
          hit_count += outside[r].triangle != lsk::LS_INVALID;
        }
        CHECK(mismatches == 0);
        CHECK(wrong_occlusion == 0);
        outside_hits += hit_count;
        if (skip == ls::LsSkip::Lookups)
          CHECK(counters.lookups == 0);
        else
          CHECK(counters.refused_angle == counters.lookups);
      }
    }
  }
  CHECK(outside_hits > 0);
  // The reference kernels and the fast path's any hit (which runs them) do not know --skip.
  const ls::Scene scene = ls::load_scene("builtin:cornell");
  const ls::Accel a = ls::build_accel(scene, ls::parse_structure("f-ls:4:4"), options(8));
  const std::vector<lsk::Ray> rays = ls::generate_rays(scene, a, ls::RayKind::Diffuse, 10, 1);
  std::vector<lsk::Hit> hits(rays.size());
  ls::LsLookup lookup;
  lookup.skip = ls::LsSkip::Lookups;
  CHECK_THROWS_AS(ls::trace_rays(a, lookup, rays.data(), hits.data(), rays.size(), false, nullptr, ls::Traversal::Reference),
                  ls::InputError);
  CHECK_THROWS_AS(ls::trace_rays(a, lookup, rays.data(), hits.data(), rays.size(), true, nullptr, ls::Traversal::Fast),
                  ls::InputError);
}

TEST_CASE("wide BVH: same answers for axis-parallel, grazing, boundary and degenerate rays", "[wide]") {
  const ls::Scene scene = random_scene(4);
  StdRng rng(99);
  std::vector<lsk::Ray> rays;
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int i = 0; i < 3000; ++i) {
    const glm::vec3 o = rng.vec(-4.0f, 4.0f);
    glm::vec3 d = rng.vec(-1.0f, 1.0f);
    switch (i % 6) {
      case 0: d = axes[i / 6 % 6]; break;                                     // parallel to two slabs
      case 1: d[i / 6 % 3] = 0.0f; break;                                     // parallel to one slab
      case 2: d[i / 6 % 3] = 1e-30f; break;                                   // denormal-sized reciprocal
      case 3: rays.push_back(make_ray(o, d, 0.5f, 3.0f)); continue;           // an interval
      case 4: rays.push_back(make_ray(glm::vec3(o.x, o.y, 0.0f), d)); continue;  // origins in grid planes
      default: break;
    }
    rays.push_back(make_ray(o, d));
  }
  rays.push_back(make_ray(glm::vec3(0.0f), glm::vec3(0.0f)));                     // zero direction
  rays.push_back(make_ray(glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f), 2.0f, 1.0f));  // empty interval
  rays.push_back(make_ray(glm::vec3(0.0f), glm::vec3(1.0f, 0.2f, 0.1f), 0.0f, std::numeric_limits<float>::quiet_NaN()));
  for (int width : {4, 8})
    for (const char* s : {"bvh", "2l-bvh", "f-ls:4:3", "2l-ls:2:3"}) {
      const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(width));
      REQUIRE(a.fast->exact_width() == width);
      require_same(a, rays, false, "special rays");
      require_same(a, rays, true, "special rays");
    }
}

TEST_CASE("wide BVH: trace_rays takes the fast path by default and the reference on request", "[wide]") {
  const ls::Scene scene = random_scene(5);
  const ls::Accel fast = ls::build_accel(scene, ls::parse_structure("f-ls:4:3"));
  CHECK(fast.traversal == ls::Traversal::Fast);
  CHECK(fast.fast != nullptr);
  CHECK(fast.bytes_wide() > 0);
  CHECK(fast.fast->exact_width() == 8);  // the default, chosen by measurement (docs/performance.md)
  ls::AccelOptions o;
  o.traversal = ls::parse_traversal("reference");
  const ls::Accel ref = ls::build_accel(scene, ls::parse_structure("f-ls:4:3"), o);
  CHECK(ref.traversal == ls::Traversal::Reference);
  CHECK_THROWS_AS(ls::parse_traversal("simd"), ls::InputError);
  o.exact_width = 2;
  CHECK_THROWS_AS(ls::build_accel(scene, ls::parse_structure("bvh"), o), ls::InputError);
}

TEST_CASE("the names of --traversal: each parses to its traversal and back, the default first, and another name is refused naming them all", "[wide]") {
  const std::vector<std::string> names = ls::traversal_names();
  REQUIRE(names.size() == 2u);
  CHECK(names.front() == ls::traversal_name(ls::AccelOptions{}.traversal));
  std::set<int> traversals;
  for (const std::string& name : names) {
    const ls::Traversal t = ls::parse_traversal(name);
    CHECK(ls::traversal_name(t) == name);
    traversals.insert(int(t));
  }
  CHECK(traversals.size() == names.size());
  try {
    ls::parse_traversal("simd");
    FAIL("no InputError");
  } catch (const ls::InputError& e) {
    const std::string what = e.what();
    CHECK(what.find("simd") != std::string::npos);
    for (const std::string& name : names) CHECK(what.find(name) != std::string::npos);
  }
}

TEST_CASE("wide BVH: a build without the fast path (the GPU port's) traces with the reference, same hits", "[wide]") {
  const ls::Scene scene = random_scene(5);
  const ls::Accel exact = ls::build_accel(scene, ls::parse_structure("bvh"));
  const std::vector<lsk::Ray> rays = ls::generate_rays(scene, exact, ls::RayKind::Diffuse, 3000, 8);
  for (const char* s : {"bvh", "2l-ls:2:3"}) {
    INFO(s);
    ls::AccelOptions o;
    o.fast_path = false;
    o.exact_width = 2;  // not checked: no fast path is made
    const ls::Accel none = ls::build_accel(scene, ls::parse_structure(s), o);
    CHECK(none.fast == nullptr);
    CHECK(none.bytes_wide() == 0);
    CHECK(none.traversal == ls::Traversal::Reference);
    const ls::Accel with = ls::build_accel(scene, ls::parse_structure(s));
    std::vector<lsk::Hit> a(rays.size()), b(rays.size());
    ls::trace_rays(none, ls::LsLookup{}, rays.data(), a.data(), rays.size(), false);
    ls::trace_rays(with, ls::LsLookup{}, rays.data(), b.data(), rays.size(), false);
    CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(lsk::Hit)) == 0);
  }
}

TEST_CASE("wide BVH: rays with infinite or NaN components take the reference kernel and agree", "[wide]") {
  const ls::Scene scene = random_scene(6);
  const float inf = kInf, nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<lsk::Ray> rays;
  StdRng rng(17);
  for (int i = 0; i < 600; ++i) {
    glm::vec3 o = rng.vec(-4.0f, 4.0f), d = rng.vec(-1.0f, 1.0f);
    const float bad = i % 2 ? inf : nan;
    switch (i % 4) {
      case 0: o[i / 4 % 3] = i % 8 < 4 ? bad : -bad; break;
      case 1: d[i / 4 % 3] = i % 8 < 4 ? bad : -bad; break;
      case 2: rays.push_back(make_ray(o, d, nan)); continue;
      default: rays.push_back(make_ray(o, d, -inf, inf)); continue;
    }
    rays.push_back(make_ray(o, d));
  }
  for (const char* s : {"bvh", "2l-bvh", "f-ls:4:3", "2l-ls:2:3"}) {
    const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(4));
    std::vector<lsk::Hit> ref(rays.size()), fast(rays.size());
    ls::trace_rays(a, ls::LsLookup{}, rays.data(), ref.data(), rays.size(), false, nullptr, ls::Traversal::Reference);
    ls::trace_rays(a, ls::LsLookup{}, rays.data(), fast.data(), rays.size(), false, nullptr, ls::Traversal::Fast);
    size_t mismatches = 0;
    for (size_t i = 0; i < rays.size(); ++i) mismatches += std::memcmp(&ref[i], &fast[i], sizeof(lsk::Hit)) != 0;
    INFO(s);
    CHECK(mismatches == 0);
  }
}

TEST_CASE("scale_pow2: the exponent-field shortcut gives the exact product, saturated and flushed as documented", "[wide]") {
  // The kernel's contract: x * 2^e exactly; +-inf when float_exponent(x) + e > 127; a zero of x's
  // sign when it is < -126 (a denormal x counts as exponent -127); zero, inf and NaN stay.
  auto expected = [](float x, int e) {
    if (x == 0.0f || std::isinf(x) || std::isnan(x)) return x;
    const int field = int((std::bit_cast<uint32_t>(x) >> 23) & 255u);
    const int ex = field - 127;
    if (ex + e > 127) return x < 0.0f ? -kInf : kInf;
    if (ex + e < -126) return 0.0f * x;
    return float(std::ldexp(double(x), e));  // exact in double, representable in float
  };
  StdRng rng(3);
  size_t checked = 0, mismatches = 0;
  for (uint32_t field = 0; field < 256; ++field)
    for (uint32_t k = 0; k < 6; ++k) {
      const uint32_t mantissa = k == 0 ? 0u : k == 1 ? 1u : k == 2 ? 0x7FFFFFu : uint32_t(rng.gen()) & 0x7FFFFFu;
      for (uint32_t sign : {0u, 0x80000000u}) {
        const float x = std::bit_cast<float>(sign | field << 23 | mantissa);
        for (int e = -260; e <= 260; ++e) {
          const float got = lsk::scale_pow2(x, e), want = expected(x, e);
          ++checked;
          if (std::isnan(want) ? !std::isnan(got) : std::bit_cast<uint32_t>(got) != std::bit_cast<uint32_t>(want)) {
            if (mismatches++ < 5) UNSCOPED_INFO("x bits " << std::hex << std::bit_cast<uint32_t>(x) << std::dec << ", e " << e);
          }
        }
      }
    }
  CHECK(checked > 1000000);
  CHECK(mismatches == 0);
}

TEST_CASE("four-lane scale_pow2 of the triangle blocks equals the kernel's", "[wide]") {
  StdRng rng(5);
  size_t mismatches = 0;
  for (int e = -126; e <= 126; ++e) {
    const ls::Int4 one_minus_e(1 - e);
    const ls::Float4 pow2_e(lsk::pow2(e));
    for (uint32_t field = 0; field < 256; ++field) {
      alignas(16) float x[4];
      for (int l = 0; l < 4; ++l) {
        const uint32_t mantissa = l == 0 ? 0u : l == 1 ? 1u : uint32_t(rng.gen()) & 0x7FFFFFu;
        x[l] = std::bit_cast<float>((l == 3 ? 0x80000000u : 0u) | field << 23 | mantissa);
      }
      alignas(16) float got[4];
      ls::block_lanes::scale_pow2(ls::Float4::load_aligned(x), one_minus_e, pow2_e).store_aligned(got);
      for (int l = 0; l < 4; ++l) {
        const float want = lsk::scale_pow2(x[l], e);
        if (!(std::isnan(want) && std::isnan(got[l])) && std::bit_cast<uint32_t>(got[l]) != std::bit_cast<uint32_t>(want))
          ++mismatches;
      }
    }
  }
  CHECK(mismatches == 0);
}

// A float of random sign and mantissa with the exponent field `field` (0: denormal or zero).
float float_with_field(StdRng& rng, uint32_t field) {
  const uint32_t mantissa = field == 0 && rng.gen() % 4 == 0 ? 0u : uint32_t(rng.gen()) & 0x7FFFFFu;
  return std::bit_cast<float>((rng.gen() % 2 ? 0x80000000u : 0u) | field << 23 | mantissa);
}

TEST_CASE("the kernels' abs clears the sign bit, as GPUs compile GLSL's: signed zeros and NaNs of either sign, every exponent", "[wide]") {
  // glm's x >= 0 ? x : -x would keep -0 and flip a NaN's sign (and compiled to a mispredicted jump).
  StdRng rng(29);
  size_t checked = 0, mismatches = 0;
  auto check = [&](float x) {
    ++checked;
    const uint32_t want = std::bit_cast<uint32_t>(x) & 0x7FFFFFFFu;
    if (std::bit_cast<uint32_t>(lsk::abs(x)) != want && mismatches++ < 5)
      UNSCOPED_INFO("x bits " << std::hex << std::bit_cast<uint32_t>(x));
  };
  for (uint32_t field = 0; field < 256; ++field)  // field 255: infinities and NaNs with random payloads
    for (int k = 0; k < 2000; ++k) check(float_with_field(rng, field));
  for (float x : {0.0f, -0.0f, kInf, -kInf, std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN(),
                  std::numeric_limits<float>::denorm_min(), -std::numeric_limits<float>::denorm_min()})
    check(x);
  const glm::vec3 v(-0.0f, -std::numeric_limits<float>::quiet_NaN(), -2.5f);
  const glm::vec3 got = lsk::abs(v);
  for (int a = 0; a < 3; ++a) CHECK(std::bit_cast<uint32_t>(got[a]) == (std::bit_cast<uint32_t>(v[a]) & 0x7FFFFFFFu));
  CHECK(checked == 256u * 2000u + 8u);
  CHECK(mismatches == 0);
}

TEST_CASE("make_block_ray's triangle ray is the kernel's make_tri_ray, bit for bit", "[wide]") {
  // Directions whose components have every exponent field (zero, denormal, normal, huge, inf, NaN),
  // either sign, ties between their magnitudes (the axis choice) and -0.
  StdRng rng(23);
  size_t checked = 0, mismatches = 0;
  auto component = [&](int kind) {
    switch (kind) {
      case 0: return 0.0f;
      case 1: return -0.0f;
      case 2: return kInf;
      case 3: return -kInf;
      case 4: return std::numeric_limits<float>::quiet_NaN();
      default: return float_with_field(rng, uint32_t(rng.gen() % 256));
    }
  };
  for (int trial = 0; trial < 200000; ++trial) {
    glm::vec3 dir;
    for (int a = 0; a < 3; ++a) dir[a] = component(trial % 4 == 0 ? int(rng.gen() % 8) : 5);
    if (trial % 5 == 1) dir[rng.gen() % 3] = dir[rng.gen() % 3];  // equal magnitudes: the tie rule of kz
    if (trial % 5 == 2) dir[rng.gen() % 3] = -dir[rng.gen() % 3];
    const glm::vec3 origin = rng.vec(-1e3f, 1e3f);
    const lsk::TriRay want = lsk::make_tri_ray(origin, dir);
    ls::BlockRay got;
    ls::make_block_ray(origin, dir, got);
    ++checked;
    // Bit for bit, a NaN (0 / 0 shear, a NaN direction) only as a NaN.
    auto same = [](float x, float y) { return (std::isnan(x) && std::isnan(y)) || std::bit_cast<uint32_t>(x) == std::bit_cast<uint32_t>(y); };
    bool ok = got.tri.dir_exp == want.dir_exp && got.tri.kx == want.kx && got.tri.ky == want.ky && got.tri.kz == want.kz &&
              same(got.tri.sx, want.sx) && same(got.tri.sy, want.sy) && same(got.tri.sz, want.sz);
    for (int a = 0; a < 3; ++a) ok = ok && same(got.tri.dir[a], want.dir[a]) && same(got.tri.origin[a], want.origin[a]);
    // The lanes broadcast from it: the origin in the sheared axes' order, the shear.
    const uint32_t axes[3] = {want.kx, want.ky, want.kz};
    for (int a = 0; a < 3; ++a) {
      ok = ok && got.axis[a] == axes[a];
      for (size_t l = 0; l < ls::Float4::size; ++l) ok = ok && same(got.origin[a].get(l), want.origin[axes[a]]);
    }
    for (size_t l = 0; l < ls::Float4::size; ++l) ok = ok && same(got.shear_x.get(l), want.sx) && same(got.shear_y.get(l), want.sy);
    if (!ok && mismatches++ < 5)
      UNSCOPED_INFO("dir bits " << std::hex << std::bit_cast<uint32_t>(dir.x) << ' ' << std::bit_cast<uint32_t>(dir.y) << ' '
                                << std::bit_cast<uint32_t>(dir.z));
  }
  CHECK(checked == 200000);
  CHECK(mismatches == 0);
}

TEST_CASE("four-lane plane normals of the triangle blocks equal the kernel's, bit for bit", "[wide]") {
  // Vertices whose edges have every exponent field (the scale's clamp at both ends, flushes to zero,
  // denormals), coincide (zero edges, the unused lanes' case), overflow to infinity, or hold an
  // infinity or a NaN (the lanes the kernel itself takes).
  StdRng rng(29);
  size_t checked = 0, mismatches = 0;
  auto coordinate = [&](int kind, uint32_t field) {
    switch (kind) {
      case 0: return 0.0f;
      case 1: return -0.0f;
      case 2: return kInf;
      case 3: return std::numeric_limits<float>::quiet_NaN();
      case 4: return 3.0e38f;
      default: return float_with_field(rng, field);
    }
  };
  for (int trial = 0; trial < 100000; ++trial) {
    ls::TriBlock block{};
    for (int l = 0; l < 4; ++l) {
      // A lane's coordinates near one exponent field, so that their differences span the range.
      const uint32_t base = uint32_t(rng.gen() % 255);
      for (int p = 0; p < 3; ++p)
        for (int a = 0; a < 3; ++a) {
          const int kind = trial % 3 == 0 ? int(rng.gen() % 12) : 5;
          const uint32_t field = uint32_t(std::clamp(int(base) + int(rng.gen() % 9) - 4, 0, 254));
          block.v[p][a][l] = coordinate(kind, field);
        }
      if (trial % 11 == 1)  // a degenerate lane: two equal vertices, or all three
        for (int a = 0; a < 3; ++a) block.v[1][a][l] = block.v[trial % 2 ? 2 : 0][a][l] = block.v[0][a][l];
    }
    ls::block_lanes::plane_normals(block);
    for (int l = 0; l < 4; ++l) {
      auto vertex = [&](int p) { return lsk::vec3(block.v[p][0][l], block.v[p][1][l], block.v[p][2][l]); };
      const lsk::vec3 want = lsk::triangle_plane_normal(vertex(0), vertex(1), vertex(2));
      ++checked;
      bool ok = true;
      for (int a = 0; a < 3; ++a)
        ok = ok && ((std::isnan(want[a]) && std::isnan(block.n[a][l])) ||
                    std::bit_cast<uint32_t>(want[a]) == std::bit_cast<uint32_t>(block.n[a][l]));
      if (!ok && mismatches++ < 5) UNSCOPED_INFO("trial " << trial << " lane " << l);
    }
  }
  CHECK(checked == 400000);
  CHECK(mismatches == 0);
}

TEST_CASE("triangle blocks: every lane gives the scalar kernel's hit, from denormal to huge coordinates", "[wide]") {
  // The block test's rescale (max, exponent clamp to [-126, 126], flush rule) against
  // lsk::ray_triangle, one lane at a time: triangles whose offsets from the origin have exponents
  // across the float range, coincide with the origin, share it as a vertex, or hold an infinity or
  // a NaN.  Expected from the kernel and offer_hit, as lsk::TraceContext::trace_leaf does.
  StdRng rng(17);
  const uint32_t ids[4] = {0u, 1u, 2u, 3u};
  lsk::TraceContext c{};
  c.tri_ids = ids;
  c.tri_instances = ids;
  size_t mismatches = 0, hits = 0, tested = 0;
  std::string first;
  for (int trial = 0; trial < 20000; ++trial) {
    const glm::vec3 origin = trial % 2 ? rng.vec(-4.0f, 4.0f) : glm::vec3(0.0f);
    glm::vec3 dir = rng.vec(-1.0f, 1.0f);
    if (trial % 7 == 0) dir[trial % 3] = 0.0f;  // axis-parallel components
    dir *= lsk::pow2(int(rng.gen() % 61) - 30);
    if (dir == glm::vec3(0.0f)) continue;
    ls::BlockRay block_ray;
    ls::make_block_ray(origin, dir, block_ray);
    // Each triangle at one scale: 2^e with e spread over the whole range, a third of them near the
    // ray (on its line, plus small offsets) so that lanes pass the edge test.
    ls::TriBlock block{};
    glm::vec3 p[4][3];
    for (int l = 0; l < 4; ++l) {
      const uint32_t field = rng.gen() % 5 == 0 ? uint32_t(rng.gen() % 3) * 127u : 1u + uint32_t(rng.gen() % 253);
      for (int k = 0; k < 3; ++k) {
        glm::vec3 offset(float_with_field(rng, field), float_with_field(rng, field), float_with_field(rng, field));
        if (l == 3)  // mixed scales within a triangle: denormal next to unit-sized coordinates (the flush rule)
          for (int a = 0; a < 3; ++a) offset[a] = float_with_field(rng, rng.gen() % 2 ? uint32_t(rng.gen() % 3) : 127u);
        if (rng.gen() % 3 == 0) offset = dir * std::abs(float_with_field(rng, field)) + offset * 0.25f;
        p[l][k] = origin + offset;
      }
      switch (rng.gen() % 16) {
        case 0: p[l][0] = origin; break;                                                // a vertex on the origin
        case 1: p[l][0] = p[l][1] = p[l][2] = origin; break;                            // all of them: m == 0
        case 2: p[l][rng.gen() % 3][rng.gen() % 3] = kInf; break;                       // an infinite coordinate
        case 3: p[l][rng.gen() % 3][rng.gen() % 3] = std::numeric_limits<float>::quiet_NaN(); break;
        case 4: p[l][2] = p[l][1]; break;                                               // degenerate: two equal vertices
        default: break;
      }
      const glm::vec3 n = lsk::triangle_plane_normal(p[l][0], p[l][1], p[l][2]);
      for (int a = 0; a < 3; ++a) {
        for (int k = 0; k < 3; ++k) block.v[k][a][l] = p[l][k][a];
        block.n[a][l] = n[a];
      }
      block.prim[l] = uint32_t(l);
    }
    for (int l = 0; l < 4; ++l) {
      const float tmax = trial % 3 == 0 ? kInf : lsk::pow2(int(rng.gen() % 200) - 100);
      lsk::Hit want{};
      want.t = tmax;
      want.instance = lsk::LS_INVALID;
      want.triangle = lsk::LS_INVALID;
      lsk::Hit got = want;
      float t, u, v;
      if (lsk::ray_triangle(block_ray.tri, 0.0f, want.t, p[l][0], p[l][1], p[l][2], t, u, v))
        lsk::offer_hit(t, u, v, ids[l], ids[l], want);
      uint32_t prim = lsk::LS_INVALID;
      ls::trace_blocks(c, &block, uint32_t(l), 1u, block_ray, 0.0f, lsk::LS_INVALID, false, got, prim);
      ++tested;
      hits += want.triangle != lsk::LS_INVALID;
      const bool same = std::memcmp(&want, &got, sizeof(lsk::Hit)) == 0 && (prim == want.triangle);
      if (!same && mismatches++ == 0) first = "trial " + std::to_string(trial) + " lane " + std::to_string(l) + ": want " +
                                              describe(want) + ", got " + describe(got);
    }
  }
  INFO(first);
  CHECK(mismatches == 0);
  CHECK(tested > 70000);
  CHECK(hits > 500);  // enough lanes pass the edge test to exercise the deciding half
}

template <int W>
void check_exact_tree() {
  const ls::Scene scene = random_scene(8);
  for (const char* s : {"bvh", "2l-bvh", "f-ls:4:3", "2l-ls:2:3", "2l-ls:0:3"}) {
    INFO(s << ", " << W << "-wide");
    const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(4));
    const std::vector<uint32_t> none;
    const std::vector<uint32_t>& node_ls = a.spec.line_space() ? a.node_ls : none;
    const std::vector<uint32_t> roots = a.spec.two_level() ? a.object_roots : std::vector<uint32_t>{0u};
    const ls::ExactWideTree<W> tree = ls::build_exact_wide_tree<W>(a.nodes, node_ls, roots);
    // The entries are the inner roots and the inner Line Space nodes.
    auto is_ls = [&](uint32_t b) { return !node_ls.empty() && node_ls[b] != lsk::LS_INVALID; };
    std::set<uint32_t> distinct(roots.begin(), roots.end());
    size_t entries = 0, ls_entries = 0, ls_leaves = 0, wrong_entries = 0;
    std::function<void(uint32_t, bool)> walk = [&](uint32_t b, bool root) {
      const lsk::BvhNode& n = a.nodes[b];
      const bool entry = n.count == 0 && (root || is_ls(b));
      wrong_entries += (tree.entry_of[b] != lsk::LS_INVALID) != entry;
      entries += entry;
      ls_entries += entry && is_ls(b);
      ls_leaves += n.count > 0 && is_ls(b);
      if (n.count == 0) {
        walk(n.first, false);
        walk(n.first + 1, false);
      }
    };
    for (uint32_t r : distinct)
      if (r != lsk::LS_INVALID) walk(r, true);
    CHECK(wrong_entries == 0);
    CHECK(entries == tree.entries);
    if (a.spec.line_space()) CHECK(ls_entries + ls_leaves == a.ls_info.ls_nodes);
    // Below each entry every triangle sits in exactly one leaf lane or Line Space lane, inside that
    // lane's box.
    for (uint32_t r = 0; r < a.nodes.size(); ++r) {
      if (tree.entry_of[r] == lsk::LS_INVALID) continue;
      std::function<void(uint32_t)> check_entry = [&](uint32_t b) {
        const lsk::BvhNode& n = a.nodes[b];
        if (tree.entry_of[b] == lsk::LS_INVALID) {
          if (n.count == 0) {
            check_entry(n.first);
            check_entry(n.first + 1);
          }
          return;
        }
        std::function<uint32_t(uint32_t)> range_count = [&](uint32_t c) -> uint32_t {
          return a.nodes[c].count > 0 ? a.nodes[c].count : range_count(a.nodes[c].first) + range_count(a.nodes[c].first + 1);
        };
        std::map<uint32_t, int> seen;
        size_t outside = 0, unused_not_nan = 0, narrow = 0, big_merged = 0, wrong_ls_lanes = 0;
        std::function<void(uint32_t)> visit = [&](uint32_t w) {
          const ls::ExactWideNode<W>& node = tree.nodes[w];
          int used = 0;
          for (int l = 0; l < W; ++l) {
            if (node.child[l] == lsk::LS_INVALID) {
              unused_not_nan += !std::isnan(node.lo[0][l]) || !std::isnan(node.hi[2][l]);
              continue;
            }
            ++used;
            if (node.count[l] == 0) {
              visit(node.child[l]);
              continue;
            }
            if (node.count[l] == ls::kLsLane) {  // a Line Space node's subtree, its own box
              const uint32_t c = node.child[l];
              wrong_ls_lanes += !is_ls(c);
              for (int ax = 0; ax < 3; ++ax) outside += a.nodes[c].lo[ax] != node.lo[ax][l] || a.nodes[c].hi[ax] != node.hi[ax][l];
              std::function<void(uint32_t)> tris_of = [&](uint32_t x) {
                if (a.nodes[x].count == 0) {
                  tris_of(a.nodes[x].first);
                  tris_of(a.nodes[x].first + 1);
                } else {
                  for (uint32_t k = 0; k < a.nodes[x].count; ++k) ++seen[a.nodes[x].first + k];
                }
              };
              tris_of(c);
              continue;
            }
            bool binary_leaf = false;  // a leaf lane is a binary leaf or a merged subtree of <= kLeafMax
            for (const lsk::BvhNode& n : a.nodes) binary_leaf |= n.count == node.count[l] && n.first == node.child[l];
            big_merged += !binary_leaf && node.count[l] > ls::ExactWideTree<W>::kLeafMax;
            for (uint32_t k = 0; k < node.count[l]; ++k) {
              const uint32_t i = node.child[l] + k;
              ++seen[i];
              for (const glm::vec4* v : {&a.tris[i].v0, &a.tris[i].v1, &a.tris[i].v2})
                for (int ax = 0; ax < 3; ++ax) outside += (*v)[ax] < node.lo[ax][l] || (*v)[ax] > node.hi[ax][l];
            }
          }
          narrow += used < 2;  // (which lanes, and how full: the least-cost test below)
        };
        visit(tree.entry_of[b]);
        CHECK(outside == 0);
        CHECK(unused_not_nan == 0);
        CHECK(narrow == 0);
        CHECK(big_merged == 0);
        CHECK(wrong_ls_lanes == 0);
        CHECK(seen.size() == range_count(b));
        size_t repeated = 0;
        for (const auto& [i, times] : seen) repeated += times != 1;
        CHECK(repeated == 0);
      };
      check_entry(r);
    }
  }
}

TEST_CASE("exact wide tree: entries, leaves and boxes, 4 and 8 wide", "[wide]") {
  check_exact_tree<4>();
  check_exact_tree<8>();
}

// A box's half area, in doubles as the collapse takes it.
double half_area(const glm::vec3& lo, const glm::vec3& hi) {
  const double x = double(hi.x) - double(lo.x), y = double(hi.y) - double(lo.y), z = double(hi.z) - double(lo.z);
  return x * y + y * z + z * x;
}

// The surface area heuristic's cost of the wide tree below an entry (ExactWideTree's model:
// kNodeCost per wide node, leaf_cost per leaf, each by the half area of its box), read off the
// built tree.
template <int W>
double built_cost(const ls::ExactWideTree<W>& tree, ls::ExactLeaves leaves, uint32_t wide, double area) {
  using Tree = ls::ExactWideTree<W>;
  double cost = area * Tree::kNodeCost;
  const ls::ExactWideNode<W>& node = tree.nodes[wide];
  for (int l = 0; l < W; ++l) {
    if (node.child[l] == lsk::LS_INVALID) continue;
    const double a = half_area(glm::vec3(node.lo[0][l], node.lo[1][l], node.lo[2][l]),
                               glm::vec3(node.hi[0][l], node.hi[1][l], node.hi[2][l]));
    cost += node.count[l] == ls::kLsLane ? a * Tree::kLookupCost
            : node.count[l] > 0          ? a * Tree::leaf_cost(leaves, node.count[l])
                                         : built_cost(tree, leaves, node.child[l], a);
  }
  return cost;
}

// The least cost of any collapse of b's subtree into a wide node, by exhaustion: every *cut* of
// the subtree below b (a set of descendants that covers each leaf once) of at most W nodes is a
// choice of lanes, and each lane is, at the least cost, a leaf (a binary leaf, or a subtree of at
// most kLeafMax triangles) or a wide node of its own; a Line Space node below b is a lane of its own.
template <int W>
struct CollapseByExhaustion {
  using Tree = ls::ExactWideTree<W>;
  const std::vector<lsk::BvhNode>& nodes;
  const std::vector<uint32_t>& node_ls;
  ls::ExactLeaves leaves;
  std::map<uint32_t, double> lane_memo;

  bool is_ls(uint32_t b) const { return !node_ls.empty() && node_ls[b] != lsk::LS_INVALID; }
  bool holds_ls(uint32_t b) const {
    return is_ls(b) || (nodes[b].count == 0 && (holds_ls(nodes[b].first) || holds_ls(nodes[b].first + 1)));
  }

  double area(uint32_t b) const { return half_area(nodes[b].lo, nodes[b].hi); }
  uint32_t count(uint32_t b) const {
    return nodes[b].count > 0 ? nodes[b].count : count(nodes[b].first) + count(nodes[b].first + 1);
  }
  // Every cut of b's subtree of at most k nodes, as the node lists.
  std::vector<std::vector<uint32_t>> cuts(uint32_t b, int k, bool top = false) const {
    std::vector<std::vector<uint32_t>> out{{b}};
    if (nodes[b].count > 0 || k < 2 || (is_ls(b) && !top)) return out;
    for (const auto& left : cuts(nodes[b].first, k - 1))
      for (const auto& right : cuts(nodes[b].first + 1, k - int(left.size()))) {
        out.push_back(left);
        out.back().insert(out.back().end(), right.begin(), right.end());
      }
    return out;
  }
  double as_node(uint32_t b) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& cut : cuts(b, W, true)) {
      if (cut.size() < 2) continue;  // {b} itself is no division
      double sum = 0.0;
      for (uint32_t c : cut) sum += as_lane(c);
      best = std::min(best, sum);
    }
    return area(b) * Tree::kNodeCost + best;
  }
  double as_lane(uint32_t b) {
    if (auto it = lane_memo.find(b); it != lane_memo.end()) return it->second;
    if (is_ls(b)) return lane_memo[b] = area(b) * Tree::kLookupCost;
    const uint32_t n = count(b);
    double best = std::numeric_limits<double>::infinity();
    if (nodes[b].count > 0 || (n <= Tree::kLeafMax && !holds_ls(b))) best = area(b) * Tree::leaf_cost(leaves, n);
    if (nodes[b].count == 0) best = std::min(best, as_node(b));
    return lane_memo[b] = best;
  }
};

template <int W>
void check_least_cost(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                      const std::vector<uint32_t>& roots, ls::ExactLeaves leaves, const std::string& what) {
  const ls::ExactWideTree<W> tree = ls::build_exact_wide_tree<W>(nodes, node_ls, roots, leaves);
  CollapseByExhaustion<W> exhaustion{nodes, node_ls, leaves, {}};
  size_t entries = 0, costlier = 0;
  std::string first;
  for (uint32_t b = 0; b < nodes.size(); ++b) {
    if (tree.entry_of[b] == lsk::LS_INVALID) continue;
    ++entries;
    const double built = built_cost(tree, leaves, tree.entry_of[b], exhaustion.area(b));
    const double least = exhaustion.as_node(b);
    if (!(std::abs(built - least) <= 1e-9 * least) && costlier++ == 0)
      first = "entry " + std::to_string(b) + ": built " + std::to_string(built) + ", least " + std::to_string(least);
  }
  INFO(what << ", " << W << "-wide: " << first);
  CHECK(entries > 0);
  CHECK(costlier == 0);
}

// The object BVHs' exact tree (triangles) and, for a two-level structure, its top level's (instances).
template <int W>
void check_least_cost(const ls::Accel& a, const std::string& what) {
  const std::vector<uint32_t>& node_ls = a.spec.line_space() ? a.node_ls : std::vector<uint32_t>{};
  const std::vector<uint32_t> roots = a.spec.two_level() ? a.object_roots : std::vector<uint32_t>{0u};
  check_least_cost<W>(a.nodes, node_ls, roots, ls::ExactLeaves::Triangles, what);
  if (a.spec.two_level()) check_least_cost<W>(a.top_nodes, {}, {0u}, ls::ExactLeaves::Instances, what + ", top level");
}

TEST_CASE("exact wide tree: each entry's collapse costs the least of all collapses (by exhaustion), 4 and 8 wide", "[wide]") {
  StdRng rng(5);
  for (int k = 0; k < 4; ++k) {  // triangle soups of 40 to 160, dense (merged leaves) and sparse
    ls::Scene scene;
    scene.name = "soup";
    scene.materials.push_back(ls::Material{});
    scene.meshes.push_back(with_face_normals(scattered_soup(rng, size_t(40 + 40 * k), 1.0f, k % 2 == 0 ? 0.3f : 0.05f)));
    scene.meshes.push_back(with_face_normals(square_grid(3 + k, 0.0f, 1.0f)));  // flat boxes
    for (uint32_t i = 0; i < uint32_t(8 + 16 * k); ++i) {  // a top level of 8 to 56 instances
      ls::Instance inst;
      inst.mesh = i % 2;
      inst.object_to_world = glm::translate(glm::mat4(1.0f), rng.vec(-4.0f, 4.0f));
      scene.instances.push_back(inst);
    }
    ls::validate_scene(scene);
    for (const char* s : {"bvh", "2l-bvh", "f-ls:3:2"}) {
      const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(4));
      const std::string what = std::string(s) + ", soup " + std::to_string(k);
      check_least_cost<4>(a, what);
      check_least_cost<8>(a, what);
    }
  }
}

TEST_CASE("triangle blocks: an exact wide node's short leaves share its blocks, none straddles two", "[wide]") {
  const ls::Scene scene = ls::load_scene("builtin:generated:20000:7:3");
  for (const char* s : {"bvh", "2l-bvh", "f-ls:6:3"}) {
    INFO(s);
    const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(8));
    const std::vector<uint32_t> roots = a.spec.two_level() ? a.object_roots : std::vector<uint32_t>{0u};
    ls::ExactWideTree<8> tree = ls::build_exact_wide_tree<8>(a.nodes, a.spec.line_space() ? a.node_ls : std::vector<uint32_t>{}, roots);
    const std::vector<ls::ExactWideNode<8>> unplaced = tree.nodes;  // leaf children: first triangles
    const ls::TriangleBlocks blocks = ls::build_triangle_blocks<8>(a.nodes, a.tris, tree);
    size_t leaves = 0, triangles = 0, wrong_lane = 0, straddling = 0, shared_with_other_node = 0, unpacked_blocks = 0;
    std::map<size_t, size_t> owner;  // block -> the wide node whose leaves use it
    for (size_t w = 0; w < tree.nodes.size(); ++w) {
      for (int l = 0; l < 8; ++l) {
        const uint32_t count = tree.nodes[w].count[l];
        if (!ls::primitive_lane(count)) continue;
        ++leaves;
        const uint32_t lane = tree.nodes[w].child[l];
        for (uint32_t k = 0; k < count; ++k) {  // the leaf's triangles, in order, from its first lane
          ++triangles;
          wrong_lane += blocks.blocks[(lane + k) / 4u].prim[(lane + k) % 4u] != unplaced[w].child[l] + k;
        }
        if (count <= 4u) straddling += lane / 4u != (lane + count - 1u) / 4u;
        unpacked_blocks += (count + 3u) / 4u;
        for (uint32_t b = lane / 4u; b <= (lane + count - 1u) / 4u; ++b)
          shared_with_other_node += !owner.emplace(b, w).second && owner[b] != w;
      }
    }
    CHECK(leaves > 0);
    CHECK(wrong_lane == 0);
    CHECK(straddling == 0);
    CHECK(shared_with_other_node == 0);
    CHECK(owner.size() < unpacked_blocks);  // packing saved blocks
    // Every triangle of a flat exact structure (Line Space structures keep those of their Line Space
    // nodes that are binary leaves apart, and a two-level one an object whose root is a leaf).
    if (std::string(s) == "bvh") CHECK(triangles == a.tris.size());
  }
}

// The exact tree and the blocks of `accel` built again, on one thread or on all.
template <int W>
std::pair<ls::ExactWideTree<W>, ls::TriangleBlocks> rebuild_fast_layout(const ls::Accel& a, int threads) {
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  const std::vector<uint32_t> roots = a.spec.two_level() ? a.object_roots : std::vector<uint32_t>{0u};
  ls::ExactWideTree<W> tree = ls::build_exact_wide_tree<W>(a.nodes, a.spec.line_space() ? a.node_ls : std::vector<uint32_t>{}, roots);
  ls::TriangleBlocks blocks = ls::build_triangle_blocks<W>(a.nodes, a.tris, tree);
  return {std::move(tree), std::move(blocks)};
}

template <int W>
void check_layout_schedule_free(const ls::Accel& a) {
  const auto [tree1, blocks1] = rebuild_fast_layout<W>(a, 1);
  const auto [tree, blocks] = rebuild_fast_layout<W>(a, 0);
  REQUIRE(tree.nodes.size() == tree1.nodes.size());
  CHECK(std::memcmp(tree.nodes.data(), tree1.nodes.data(), tree.nodes.size() * sizeof(tree.nodes[0])) == 0);
  CHECK(tree.entry_of == tree1.entry_of);
  CHECK(tree.entries == tree1.entries);
  REQUIRE(blocks.blocks.size() == blocks1.blocks.size());
  CHECK(std::memcmp(blocks.blocks.data(), blocks1.blocks.data(), blocks.blocks.size() * sizeof(ls::TriBlock)) == 0);
  CHECK(blocks.lane_of == blocks1.lane_of);
  // Depth first: a wide node's inner children follow it, each subtree before the next lane's.
  size_t misplaced = 0;
  std::function<uint32_t(uint32_t)> end_of = [&](uint32_t w) {  // one past w's subtree
    uint32_t next = w + 1;
    for (int l = 0; l < W; ++l)
      if (tree.nodes[w].child[l] != lsk::LS_INVALID && tree.nodes[w].count[l] == 0) {
        misplaced += tree.nodes[w].child[l] != next;
        next = end_of(tree.nodes[w].child[l]);
      }
    return next;
  };
  uint32_t next = 0;
  std::vector<uint32_t> entry_nodes;
  for (uint32_t e : tree.entry_of)
    if (e != lsk::LS_INVALID) entry_nodes.push_back(e);
  std::sort(entry_nodes.begin(), entry_nodes.end());
  for (uint32_t e : entry_nodes) {
    misplaced += e != next;
    next = end_of(e);
  }
  CHECK(next == tree.nodes.size());
  CHECK(misplaced == 0);
}

TEST_CASE("exact wide tree and triangle blocks: the same bytes on one thread as on all, depth first", "[wide]") {
  // Large enough that the collapse and the SAH split into parallel tasks (subtrees over 4,096
  // triangles); two-level structures take their objects as tasks.
  const ls::Scene scene = ls::load_scene("builtin:generated:30000:12:5");
  for (const char* s : {"bvh", "2l-bvh", "f-ls:4:3"}) {
    INFO(s);
    const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(4));
    check_layout_schedule_free<4>(a);
    check_layout_schedule_free<8>(a);
  }
}

TEST_CASE("wide BVH: the candidate search on the fast path stores the reference kernel's candidates, every shaft", "[wide]") {
  struct Case {
    ls::Scene scene;
    std::string name;
    std::vector<const char*> structures;
  };
  std::vector<Case> cases;
  cases.push_back({ls::load_scene("builtin:cornell"), "builtin:cornell", {"f-ls:6:3", "2l-ls:2:3"}});
  cases.push_back({ls::load_scene("builtin:generated:30000:12:5"), "builtin:generated:30000:12:5", {"f-ls:8:2", "2l-ls:0:3"}});
  cases.push_back({random_scene(9), "random scene 9", {"f-ls:4:3", "2l-ls:3:2"}});
  for (const Case& k : cases)
    for (const char* s : k.structures)
      for (int further : {0, 3}) {
        ls::AccelOptions o = options(4);
        o.ls.further_rays = further;
        const ls::Accel a = ls::build_accel(k.scene, ls::parse_structure(s), o);
        REQUIRE(a.ls_info.ls_nodes > 0);
        lsk::TraceContext c = ls::trace_context(a);
        c.ls_enabled = 0;
        const uint32_t instance = ls::ls_search_instance(a);
        size_t shafts = 0, mismatches = 0, found = 0;
        for (const lsk::LsNode& ls_node : a.ls_nodes)
          for (uint32_t shaft = 0; shaft < lsk::ls_shaft_count(ls_node.n); ++shaft) {
            const uint32_t want = c.ls_find_candidate(ls_node.node, ls_node, shaft, uint32_t(further), instance);
            mismatches += c.ls_candidate(ls_node, shaft) != want;
            found += want != lsk::LS_INVALID;
            ++shafts;
          }
        INFO(k.name << ", " << s << ", further rays " << further << ": " << shafts << " shafts");
        CHECK(mismatches == 0);
        CHECK(found > 0);
      }
}

TEST_CASE("wide BVH: occlusion queries miss exactly where the reference's any hit misses, and report a real hit", "[wide]") {
  auto check = [](const ls::Accel& a, const std::vector<lsk::Ray>& rays, const std::string& what) {
    INFO(what << ", " << a.spec.name());
    std::vector<lsk::Hit> ref(rays.size()), occ(rays.size());
    lsk::LsCounters ref_counters{}, occ_counters{};
    ls::trace_rays(a, ls::LsLookup{}, rays.data(), ref.data(), rays.size(), true, &ref_counters, ls::Traversal::Reference);
    ls::trace_occlusion(a, ls::LsLookup{}, rays.data(), occ.data(), rays.size(), &occ_counters, ls::Traversal::Fast);
    size_t blocked = 0, wrong_blocking = 0, unverified = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      const bool ref_blocked = ref[i].triangle != lsk::LS_INVALID;
      wrong_blocking += ref_blocked != (occ[i].triangle != lsk::LS_INVALID);
      if (!ref_blocked || occ[i].triangle == lsk::LS_INVALID) continue;
      ++blocked;
      if (a.spec.line_space()) {  // a triangle's hit or a lookup's plane hit: inside the ray's interval
        unverified += !(occ[i].t >= rays[i].tmin && occ[i].t <= rays[i].tmax);
        continue;
      }
      // The reported triangle is hit by the kernel at the reported t, inside the ray's interval.
      size_t k = 0;
      while (k < a.tri_ids.size() && !(a.tri_ids[k] == occ[i].triangle &&
                                       (a.spec.two_level() || a.tri_instances[k] == occ[i].instance)))
        ++k;
      glm::vec3 o = rays[i].origin, d = rays[i].dir;
      if (a.spec.two_level()) {
        bool found = false;
        for (const lsk::InstanceRecord& rec : a.instances)
          if (rec.instance == occ[i].instance) {
            lsk::TraceContext c = ls::trace_context(a);
            c.instance_ray(rec, rays[i].origin, rays[i].dir, o, d);
            // the object's triangles: those in the subtree of rec.root with this id
            for (k = 0; k < a.tri_ids.size(); ++k) {
              if (a.tri_ids[k] != occ[i].triangle) continue;
              float t, u, v;
              if (lsk::ray_triangle(lsk::make_tri_ray(o, d), rays[i].tmin, rays[i].tmax, glm::vec3(a.tris[k].v0),
                                    glm::vec3(a.tris[k].v1), glm::vec3(a.tris[k].v2), t, u, v) &&
                  t == occ[i].t)
                found = true;
            }
          }
        unverified += !found;
        continue;
      }
      float t, u, v;
      const bool hit = k < a.tris.size() && lsk::ray_triangle(lsk::make_tri_ray(o, d), rays[i].tmin, rays[i].tmax,
                                                               glm::vec3(a.tris[k].v0), glm::vec3(a.tris[k].v1),
                                                               glm::vec3(a.tris[k].v2), t, u, v);
      unverified += !(hit && t == occ[i].t && u == occ[i].u && v == occ[i].v);
    }
    CHECK(wrong_blocking == 0);
    CHECK(unverified == 0);
    CHECK(blocked > 0);
  };
  const ls::Scene cornell = ls::load_scene("builtin:cornell");
  const ls::Scene random = random_scene(10);
  for (const ls::Scene* scene : {&cornell, &random}) {
    const ls::Accel exact = ls::build_accel(*scene, ls::parse_structure("bvh"));
    const std::vector<lsk::Ray> shadow = ls::generate_rays(*scene, exact, ls::RayKind::Shadow, 3000, 21);
    const std::vector<lsk::Ray> diffuse = ls::generate_rays(*scene, exact, ls::RayKind::Diffuse, 3000, 22);
    for (const char* s : {"bvh", "2l-bvh", "f-ls:4:3", "2l-ls:2:3"}) {
      const ls::Accel a = ls::build_accel(*scene, ls::parse_structure(s), options(4));
      check(a, shadow, scene->name + ", shadow rays");
      check(a, diffuse, scene->name + ", diffuse rays");
    }
  }
}
