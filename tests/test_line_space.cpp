// The Line Space against brute force and against the exact structures, at the extremes.
#include "common/kernels/line_space.h"
#include "common/structure/accel.h"
#include "common/structure/trace_context.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <chrono>
#include <cmath>
#include <cstring>
#include <random>
#include <set>

using namespace ls;
using namespace test_support;

namespace {

float uniform(std::mt19937& rng) { return float(rng() >> 8) * (1.0f / 16777216.0f); }

std::vector<lsk::Ray> random_rays(size_t count, uint32_t seed, glm::vec3 lo = glm::vec3(-0.5f), glm::vec3 hi = glm::vec3(1.5f)) {
  std::mt19937 rng(seed);
  std::vector<lsk::Ray> rays(count);
  for (lsk::Ray& r : rays) {
    for (int a = 0; a < 3; ++a) r.origin[a] = lo[a] + (hi[a] - lo[a]) * uniform(rng);
    glm::vec3 d;
    do d = glm::vec3(uniform(rng), uniform(rng), uniform(rng)) * 2.0f - 1.0f;
    while (glm::dot(d, d) < 1e-4f || glm::dot(d, d) > 1.0f);
    r.dir = glm::normalize(d);
    r.tmin = 0.0f;
    r.tmax = lsk::ls_infinity();
  }
  return rays;
}

std::vector<lsk::Hit> trace_all(const Accel& a, const std::vector<lsk::Ray>& rays, bool any_hit = false,
                                lsk::LsCounters* counters = nullptr, const LsLookup& lookup = {}) {
  std::vector<lsk::Hit> hits(rays.size());
  trace_rays(a, lookup, rays.data(), hits.data(), rays.size(), any_hit, counters);
  return hits;
}

bool same_bits(const std::vector<lsk::Hit>& a, const std::vector<lsk::Hit>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(lsk::Hit)) == 0;
}

// Rays from inside the unit cube (where unit_cube_soup lies, so inside its LS boxes) with intervals
// [tmin, tmax] of random start and length.
std::vector<lsk::Ray> interval_rays() {
  std::mt19937 rng(23);
  std::vector<lsk::Ray> rays = random_rays(20000, 29, glm::vec3(0.0f), glm::vec3(1.0f));
  for (lsk::Ray& r : rays) {
    r.tmin = 0.05f * uniform(rng);
    r.tmax = r.tmin + 0.5f * uniform(rng);
  }
  return rays;
}

// Every reported hit lies in its ray's [tmin, tmax]; returns how many were reported.
size_t require_in_interval(const std::vector<lsk::Hit>& hits, const std::vector<lsk::Ray>& rays) {
  size_t count = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (hits[i].triangle == lsk::LS_INVALID) continue;
    ++count;
    REQUIRE(hits[i].t >= rays[i].tmin);
    REQUIRE(hits[i].t <= rays[i].tmax);
  }
  return count;
}

// The paper's behaviour: every node at depth D gets a Line Space, however small its subtree.
AccelOptions paper() {
  AccelOptions o;
  o.ls.min_triangles = 0;
  return o;
}

// The lookup at a refusal angle, with the behind mode.
LsLookup angle(float degrees, LsBehind behind = LsBehind::Exact) {
  LsLookup l;
  l.angle_degrees = degrees;
  l.behind = behind;
  return l;
}

}  // namespace

TEST_CASE("the shaft index is a bijection onto 0..30 N^4 - 1 for N from 1 to 12", "[line_space]") {
  for (uint32_t n = 1; n <= 12; ++n) {
    const uint32_t patches = 6 * n * n, shafts = lsk::ls_shaft_count(n);
    REQUIRE(shafts == 30 * n * n * n * n);
    std::vector<char> seen(shafts, 0);
    uint32_t pairs = 0;
    for (uint32_t s = 0; s < patches; ++s)
      for (uint32_t e = 0; e < patches; ++e) {
        if (s / (n * n) == e / (n * n)) continue;  // same face: no shaft
        const uint32_t idx = lsk::ls_shaft_index(s, e, n);
        REQUIRE(idx < shafts);
        REQUIRE(!seen[idx]);
        seen[idx] = 1;
        uint32_t s2, e2;
        lsk::ls_shaft_patches(idx, n, s2, e2);
        REQUIRE(s2 == s);
        REQUIRE(e2 == e);
        ++pairs;
      }
    REQUIRE(pairs == shafts);
  }
}

TEST_CASE("a ray through two patch points finds that shaft", "[line_space]") {
  const glm::vec3 lo(-1.0f, 0.5f, 2.0f), hi(3.0f, 0.75f, 7.0f);
  for (uint32_t n : {1u, 2u, 3u, 6u, 10u}) {
    const glm::vec3 scale = float(n) / (hi - lo);
    const float inv_n = 1.0f / float(n);
    uint32_t checked = 0;
    for (uint32_t shaft = 0; shaft < lsk::ls_shaft_count(n); shaft += (n > 3 ? 97 : 1)) {
      uint32_t s, e;
      lsk::ls_shaft_patches(shaft, n, s, e);
      for (float off : {0.5f, 0.1f, 0.9f}) {
        const glm::vec3 a = lsk::ls_patch_point(lo, hi, s, n, inv_n, off, 1.0f - off);
        const glm::vec3 b = lsk::ls_patch_point(lo, hi, e, n, inv_n, 1.0f - off, off);
        // Start the ray outside, before a, so the entry is a genuine entry.
        const glm::vec3 d = b - a;
        const glm::vec3 o = a - 0.25f * d;
        uint32_t found;
        float t_in, t_out;
        REQUIRE(lsk::ls_line_shaft(o, d, lsk::safe_reciprocal(d), lo, hi, scale, n, found, t_in, t_out));
        INFO("n " << n << " shaft " << shaft << " offset " << off);
        REQUIRE(found == shaft);
        ++checked;
      }
    }
    REQUIRE(checked > 0);
  }
}

TEST_CASE("edge and corner and face-grazing lines map consistently", "[line_space]") {
  const glm::vec3 lo(0.0f), hi(1.0f);
  const uint32_t n = 4;
  const glm::vec3 scale(4.0f);
  uint32_t shaft;
  float t_in, t_out;
  // Through two opposite corners: enters at (0,0,0), ties go to the lowest axis -> face -X.
  glm::vec3 d(1.0f, 1.0f, 1.0f);
  REQUIRE(lsk::ls_line_shaft(glm::vec3(-1.0f), d, lsk::safe_reciprocal(d), lo, hi, scale, n, shaft, t_in, t_out));
  uint32_t s, e;
  lsk::ls_shaft_patches(shaft, n, s, e);
  CHECK(s == lsk::ls_patch_index(0, 0, 0, n));          // -X face, corner patch
  CHECK(e == lsk::ls_patch_index(1, n - 1, n - 1, n));  // +X face, far corner patch
  CHECK(t_in == 1.0f);
  CHECK(t_out == 2.0f);
  // Along an edge of the box (y = 0, z = 0), axis-parallel: enters -X and leaves +X.
  d = glm::vec3(1.0f, 0.0f, 0.0f);
  REQUIRE(lsk::ls_line_shaft(glm::vec3(-1.0f, 0.0f, 0.0f), d, lsk::safe_reciprocal(d), lo, hi, scale, n, shaft, t_in, t_out));
  lsk::ls_shaft_patches(shaft, n, s, e);
  CHECK(s / (n * n) == 0u);
  CHECK(e / (n * n) == 1u);
  // Negative zero components behave like positive zeros.
  d = glm::vec3(1.0f, -0.0f, -0.0f);
  uint32_t shaft2;
  REQUIRE(lsk::ls_line_shaft(glm::vec3(-1.0f, 0.0f, 0.0f), d, lsk::safe_reciprocal(d), lo, hi, scale, n, shaft2, t_in, t_out));
  CHECK(shaft2 == shaft);
  // A line lying in the face z = 0 along a diagonal enters -X/-Y and leaves +X/+Y: a valid shaft;
  // a line that misses the box gives none.
  d = glm::vec3(0.0f, 0.0f, 1.0f);
  CHECK_FALSE(lsk::ls_line_shaft(glm::vec3(2.0f, 2.0f, -1.0f), d, lsk::safe_reciprocal(d), lo, hi, scale, n, shaft, t_in, t_out));
}

TEST_CASE("every stored candidate equals a brute-force search over its subtree", "[line_space]") {
  for (bool two_level : {false, true})
    for (int n : {1, 2, 3}) {
      const Scene scene = single_mesh_scene(unit_cube_soup(300, 7 + uint32_t(n)));
      StructureSpec spec = parse_structure(std::string(two_level ? "2l-ls:" : "f-ls:") + "2:" + std::to_string(n));
      AccelOptions opt = paper();
      opt.ls.further_rays = 4;
      const Accel a = build_accel(scene, spec, opt);
      REQUIRE(a.ls_info.ls_nodes > 0);
      const uint32_t un = uint32_t(n);
      const float inv_n = 1.0f / float(n);
      size_t compared = 0, nonempty = 0;
      for (const lsk::LsNode& ls : a.ls_nodes) {
        lsk::TraceContext c = trace_context(a);
        for (uint32_t shaft = 0; shaft < lsk::ls_shaft_count(un); ++shaft) {
          uint32_t s, e;
          lsk::ls_shaft_patches(shaft, un, s, e);
          uint32_t expect = lsk::LS_INVALID;
          for (uint32_t k = 0; k <= 4 && expect == lsk::LS_INVALID; ++k) {
            const glm::vec4 off = lsk::ls_search_offsets(k);
            const glm::vec3 p = lsk::ls_patch_point(ls.lo, ls.hi, s, un, inv_n, off.x, off.y);
            const glm::vec3 q = lsk::ls_patch_point(ls.lo, ls.hi, e, un, inv_n, off.z, off.w);
            const lsk::TriRay tr = lsk::make_tri_ray(p, q - p);
            float best = 1.0f;
            uint32_t best_id = lsk::LS_INVALID;
            for (uint32_t i = ls.range_first; i < ls.range_first + ls.range_count; ++i) {
              float t, u, v;
              const lsk::Triangle& tri = a.tris[i];
              if (lsk::ray_triangle(tr, 0.0f, best, glm::vec3(tri.v0), glm::vec3(tri.v1), glm::vec3(tri.v2), t, u, v) &&
                  (t < best || best_id == lsk::LS_INVALID || a.tri_ids[i] < a.tri_ids[best_id])) {
                best = t;
                best_id = i;
              }
            }
            expect = best_id;
          }
          const uint32_t got = c.ls_candidate(ls, shaft);
          INFO("two_level " << two_level << " n " << n << " node " << ls.node << " shaft " << shaft);
          REQUIRE(got == expect);
          ++compared;
          nonempty += got != lsk::LS_INVALID;
        }
      }
      CHECK(nonempty > 0);
      CHECK(nonempty < compared);
    }
}

TEST_CASE("a refusal angle of 0 gives exactly the exact structure's hits", "[line_space]") {
  const Scene scene = single_mesh_scene(unit_cube_soup(2000, 3), {glm::mat4(1.0f), glm::translate(glm::mat4(1.0f), glm::vec3(0.3f, 0.1f, 0.0f))});
  const std::vector<lsk::Ray> rays = random_rays(20000, 11);
  for (const char* pair : {"bvh f-ls:4:3", "bvh f-ls:0:6", "2l-bvh 2l-ls:2:4", "2l-bvh 2l-ls:0:1"}) {
    const std::string p(pair);
    const std::string exact_name = p.substr(0, p.find(' ')), ls_name = p.substr(p.find(' ') + 1);
    const Accel exact = build_accel(scene, parse_structure(exact_name), paper());
    const Accel approx = build_accel(scene, parse_structure(ls_name), paper());
    REQUIRE(approx.ls_info.ls_nodes > 0);
    INFO(ls_name);
    lsk::LsCounters counters{};
    REQUIRE(same_bits(trace_all(exact, rays), trace_all(approx, rays, false, &counters, angle(0.0f))));
    REQUIRE(same_bits(trace_all(exact, rays, true), trace_all(approx, rays, true, nullptr, angle(0.0f))));
    CHECK(counters.lookups > 0);
    CHECK(counters.accepted == 0);
    CHECK(counters.empty == 0);
  }
}

TEST_CASE("a refusal angle of 0 gives exactly the exact hits on the built-in cornell scene", "[line_space]") {
  const Scene scene = load_scene("builtin:cornell");
  const Accel exact_flat = build_accel(scene, parse_structure("bvh"), paper());
  const Accel exact_2l = build_accel(scene, parse_structure("2l-bvh"), paper());
  const std::vector<lsk::Ray> rays = generate_rays(scene, exact_flat, RayKind::Diffuse, 20000, 5);
  const auto flat = trace_all(exact_flat, rays), two = trace_all(exact_2l, rays);
  REQUIRE(same_bits(flat, trace_all(build_accel(scene, parse_structure("f-ls:6:6"), paper()), rays, false, nullptr, angle(0.0f))));
  REQUIRE(same_bits(two, trace_all(build_accel(scene, parse_structure("2l-ls:2:4"), paper()), rays, false, nullptr, angle(0.0f))));
  // With the default angle the approximations do change some hits: the test above can fail.
  CHECK_FALSE(same_bits(two, trace_all(build_accel(scene, parse_structure("2l-ls:2:4"), paper()), rays)));
}

TEST_CASE("on one large planar mesh every accepted approximation lands on the plane", "[line_space]") {
  const Scene scene = single_mesh_scene(square_grid(64));
  std::mt19937 rng(5);
  std::vector<lsk::Ray> rays(20000);
  for (lsk::Ray& r : rays) {
    r.origin = glm::vec3(uniform(rng) * 4.0f - 2.0f, uniform(rng) * 4.0f - 2.0f, 0.5f + uniform(rng));
    r.dir = glm::normalize(glm::vec3(uniform(rng) - 0.5f, uniform(rng) - 0.5f, -0.2f - uniform(rng)));
    r.tmin = 0.0f;
    r.tmax = lsk::ls_infinity();
  }
  for (const char* name : {"f-ls:3:6", "2l-ls:0:4", "f-ls:6:2"}) {
    const Accel a = build_accel(scene, parse_structure(name), paper());
    lsk::LsCounters counters{};
    const std::vector<lsk::Hit> hits = trace_all(a, rays, false, &counters, angle(89.0f));
    INFO(name);
    REQUIRE(counters.accepted > 0);
    for (size_t i = 0; i < rays.size(); ++i) {
      if (hits[i].triangle == lsk::LS_INVALID) continue;
      const float t_plane = -rays[i].origin.z / rays[i].dir.z;
      REQUIRE(hits[i].t == Approx(t_plane).epsilon(1e-5));
    }
  }
}

TEST_CASE("degenerate configurations: flat boxes and D = 0 and D past the leaves and N = 1", "[line_space]") {
  // One quad: a box of zero thickness.  Its Line Space must still find it.
  Mesh quad;
  quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  const Scene flat = single_mesh_scene(quad);
  std::vector<lsk::Ray> down;
  for (int i = 0; i < 100; ++i) {
    lsk::Ray r;
    r.origin = glm::vec3(0.05f + 0.008f * float(i), 0.5f + 0.004f * float(i), 1.0f);  // all land on the quad
    r.dir = glm::normalize(glm::vec3(0.1f, -0.05f, -1.0f));
    r.tmin = 0.0f;
    r.tmax = lsk::ls_infinity();
    down.push_back(r);
  }
  for (const char* name : {"f-ls:0:1", "f-ls:0:6", "2l-ls:0:3", "2l-ls:0:2"}) {
    const Accel a = build_accel(flat, parse_structure(name), paper());
    const Accel exact = build_accel(flat, parse_structure("bvh"), paper());
    INFO(name);
    REQUIRE(a.ls_info.ls_nodes > 0);
    const auto got = trace_all(a, down, false, nullptr, angle(89.0f)), want = trace_all(exact, down);
    for (size_t i = 0; i < down.size(); ++i) {
      REQUIRE(got[i].triangle != lsk::LS_INVALID);  // no ray slips through the flat LS
      REQUIRE(got[i].t == Approx(want[i].t).epsilon(1e-5));
    }
  }
  // Depth past the leaves: no LS node at all, and the exact structure's answers.
  const Scene soup = single_mesh_scene(unit_cube_soup(500, 9));
  const Accel deep = build_accel(soup, parse_structure("f-ls:40:2"), paper());
  REQUIRE(deep.ls_info.ls_nodes == 0);
  const std::vector<lsk::Ray> rays = random_rays(5000, 4);
  REQUIRE(same_bits(trace_all(deep, rays), trace_all(build_accel(soup, parse_structure("bvh"), paper()), rays)));
  // D = 0: exactly one LS node per BVH (F) or per unique object (2L).
  CHECK(build_accel(soup, parse_structure("f-ls:0:2"), paper()).ls_info.ls_nodes == 1);
  CHECK(build_accel(soup, parse_structure("2l-ls:0:2"), paper()).ls_info.ls_nodes == 1);
  // The minimum subtree size skips small nodes.
  AccelOptions big_only = paper();
  big_only.ls.min_triangles = 1000;
  CHECK(build_accel(soup, parse_structure("f-ls:0:2"), big_only).ls_info.ls_nodes == 0);
  // The default skips subtrees of fewer than 8 triangles (measured: docs/performance.md, "Line Space
  // parameters"); the paper's 0 keeps them.
  const Accel deep_default = build_accel(soup, parse_structure("f-ls:7:2"));
  const Accel deep_paper = build_accel(soup, parse_structure("f-ls:7:2"), paper());
  REQUIRE(deep_paper.ls_info.ls_nodes > deep_default.ls_info.ls_nodes);
  for (const lsk::LsNode& ls : deep_default.ls_nodes) REQUIRE(ls.range_count >= 8u);
}

TEST_CASE("Line Space hits respect the ray interval, origins inside LS boxes included", "[line_space]") {
  // Origins inside the soup's LS boxes: a candidate behind the origin must be refused, never reported.
  // From inside, exact never takes the shaft's first candidate; reverse does, when its plane hit lies
  // ahead, so it is the mode whose accepted answers from inside are checked here.
  const Scene scene = single_mesh_scene(unit_cube_soup(3000, 17));
  const std::vector<lsk::Ray> rays = interval_rays();
  for (const char* name : {"f-ls:0:4", "f-ls:3:6", "2l-ls:2:3"}) {
    const Accel a = build_accel(scene, parse_structure(name), paper());
    INFO(name);
    lsk::LsCounters exact{}, reverse{};
    const std::vector<lsk::Hit> exact_hits = trace_all(a, rays, false, &exact, angle(89.0f));
    const std::vector<lsk::Hit> hits = trace_all(a, rays, false, &reverse, angle(89.0f, LsBehind::Reverse));
    CHECK(exact.refused_behind > 0);
    CHECK(reverse.refused_beyond > 0);
    CHECK(reverse.accepted > 0);
    CHECK(require_in_interval(exact_hits, rays) > 0);
    CHECK(require_in_interval(hits, rays) > 0);
    for (const LsLookup& lookup : {angle(89.0f), angle(89.0f, LsBehind::Reverse)})  // any-hit answers stay inside the interval too
      require_in_interval(trace_all(a, rays, true, nullptr, lookup), rays);
  }
}

TEST_CASE("from inside an LS box exact and empty never take the first candidate, so rays leaving a sphere keep off its neighbouring facets", "[line_space]") {
  // A closed sphere is convex: a ray that leaves one of its facets outwards (from just off it, within
  // 40 degrees of its normal) meets nothing.  Seen from such an origin, the shaft's first candidate
  // lies behind it or is a facet beside the one it leaves, whose plane it crosses just ahead.
  const Scene scene = single_mesh_scene(closed_sphere(1.0f, 24, 48));
  const Mesh& mesh = scene.meshes[0];
  std::mt19937 rng(31);
  std::vector<lsk::Ray> leaving;
  while (leaving.size() < 20000) {
    const glm::uvec3 t = mesh.triangles[rng() % mesh.triangles.size()];
    const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
    const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
    const float u = uniform(rng), v = uniform(rng);
    if (u + v > 1.0f) continue;
    const glm::vec3 d = glm::normalize(glm::vec3(uniform(rng), uniform(rng), uniform(rng)) * 2.0f - 1.0f);
    const glm::vec3 dir = glm::normalize(n + 0.8f * d);
    if (glm::dot(dir, n) < std::cos(glm::radians(40.0f))) continue;
    leaving.push_back(make_ray(a + u * (b - a) + v * (c - a) + 1e-4f * n, dir));
  }
  const std::vector<lsk::Hit> bvh = trace_all(build_accel(scene, parse_structure("bvh"), paper()), leaving);
  for (const lsk::Hit& h : bvh) REQUIRE(h.triangle == lsk::LS_INVALID);
  // Rays from outside the sphere's bounds at it, so that exact mode's acceptances are still seen.
  std::vector<lsk::Ray> towards;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 o(0.3f * uniform(rng) - 0.15f, 0.3f * uniform(rng) - 0.15f, 3.0f);
    towards.push_back(make_ray(o, glm::normalize(-o)));
  }
  // Boxes of a few dozen facets, so that most of a leaving ray's lookups are from inside one.
  for (const char* name : {"f-ls:3:6", "f-ls:5:6", "2l-ls:2:6"}) {
    INFO(name);
    const Accel a = build_accel(scene, parse_structure(name), paper());
    auto false_hits = [&](const LsLookup& lookup, lsk::LsCounters& counters) {
      size_t n = 0;
      for (const lsk::Hit& h : trace_all(a, leaving, false, &counters, lookup)) n += h.triangle != lsk::LS_INVALID;
      return n;
    };
    // reverse keeps the first candidate's answer from inside: its false hits show that these rays
    // meet the case.
    lsk::LsCounters reverse{};
    const size_t reverse_false = false_hits(angle(60.0f, LsBehind::Reverse), reverse);
    CHECK(reverse_false > leaving.size() / 10);
    for (LsBehind behind : {LsBehind::Exact, LsBehind::Empty}) {
      INFO(ls_behind_name(behind));
      // What is left is the infinite plane's error on lookups from outside a box the ray passes
      // through: under a hundredth of reverse's.
      lsk::LsCounters counters{};
      CHECK(false_hits(angle(60.0f, behind), counters) * 100 < reverse_false);
      CHECK(counters.accepted * 100 < reverse.accepted);
      CHECK(counters.refused_behind > 0);
      lsk::LsCounters outside{};
      trace_all(a, towards, false, &outside, angle(60.0f, behind));
      CHECK(outside.accepted > 0);
    }
  }
}

TEST_CASE("Line Space hits respect the ray interval with --ls-behind reverse and empty, which refuse fewer as behind", "[line_space]") {
  const Scene scene = single_mesh_scene(unit_cube_soup(3000, 17));
  const std::vector<lsk::Ray> rays = interval_rays();
  const LsLookup reverse = angle(89.0f, LsBehind::Reverse), empty = angle(89.0f, LsBehind::Empty);
  for (const char* name : {"f-ls:0:4", "f-ls:3:6", "2l-ls:2:3"}) {
    INFO(name);
    lsk::LsCounters exact_counters{}, reverse_counters{}, empty_counters{};
    const Accel a = build_accel(scene, parse_structure(name), paper());  // one build: the lookup alone differs
    trace_all(a, rays, false, &exact_counters, angle(89.0f));
    const std::vector<lsk::Hit> hits = trace_all(a, rays, false, &reverse_counters, reverse);
    const std::vector<lsk::Hit> empty_hits = trace_all(a, rays, false, &empty_counters, empty);
    // Behind the origin answers with reverse; before the node's box (an origin outside it) refuses
    // in both modes.
    REQUIRE(exact_counters.refused_behind > 0);
    CHECK(reverse_counters.refused_behind < exact_counters.refused_behind);
    // The behind refusals became answers: more accepted or empty, the same lookups before them.
    CHECK(reverse_counters.accepted + reverse_counters.empty > exact_counters.accepted + exact_counters.empty);
    // empty: some of reverse's "nothing ahead" answers (those of the surface the ray leaves and of an
    // empty reverse shaft), and every other behind lookup refused as in exact mode.  From inside the
    // box exact refuses every shaft that is not empty as behind, without reading its candidate, where
    // empty names the reason (angle, past the window, parallel).  Exactly so where a ray makes one
    // lookup (the root's); elsewhere the answers change which nodes a ray reaches.
    if (std::string(name) == "f-ls:0:4") {
      CHECK(empty_counters.lookups == exact_counters.lookups);
      CHECK(empty_counters.empty <= reverse_counters.empty);
      CHECK(empty_counters.accepted == exact_counters.accepted);
      CHECK(empty_counters.refused_no_shaft == exact_counters.refused_no_shaft);
      CHECK(empty_counters.refused_angle >= exact_counters.refused_angle);
      CHECK(empty_counters.refused_behind + empty_counters.refused_angle + empty_counters.refused_beyond +
                empty_counters.refused_parallel + (empty_counters.empty - exact_counters.empty) ==
            exact_counters.refused_behind + exact_counters.refused_angle + exact_counters.refused_beyond +
                exact_counters.refused_parallel);
    }
    CHECK(empty_counters.empty > exact_counters.empty);
    CHECK(empty_counters.refused_behind < exact_counters.refused_behind);
    CHECK(empty_counters.refused_behind > reverse_counters.refused_behind);
    CHECK(require_in_interval(hits, rays) > 0);
    CHECK(require_in_interval(empty_hits, rays) > 0);
    require_in_interval(trace_all(a, rays, true, nullptr, reverse), rays);
    require_in_interval(trace_all(a, rays, true, nullptr, empty), rays);
  }
  // A refusal angle of 0 still refuses everything: the exact structure's hits.
  const std::vector<lsk::Hit> bvh = trace_all(build_accel(scene, parse_structure("bvh"), paper()), rays);
  const Accel fls = build_accel(scene, parse_structure("f-ls:3:6"), paper());
  for (LsBehind behind : {LsBehind::Reverse, LsBehind::Empty})
    REQUIRE(same_bits(trace_all(fls, rays, false, nullptr, angle(0.0f, behind)), bvh));
}

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
}  // namespace

TEST_CASE("behind the origin with --ls-behind reverse: from inside the box the reverse shaft's candidate answers, or says nothing is ahead, and with empty only the latter", "[line_space]") {
  // Two parallel planes z = 0 and z = 1 and a wall at x = -0.9 that makes the box reach z = -1 .. 2,
  // so that neither plane lies on a face of the Line Space box.
  Mesh m;
  auto add_quad = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, glm::vec3 n) {
    const uint32_t base = uint32_t(m.positions.size());
    for (const glm::vec3& p : {a, b, c, d}) {
      m.positions.push_back(p);
      m.normals.push_back(n);
    }
    m.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
    m.triangles.push_back(glm::uvec3(base, base + 2, base + 3));
  };
  for (float z : {0.0f, 1.0f}) add_quad({-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}, {0, 0, 1});
  add_quad({-0.9f, -1, -1}, {-0.9f, 1, -1}, {-0.9f, 1, 2}, {-0.9f, -1, 2}, {1, 0, 0});
  const Scene scene = single_mesh_scene(m);
  auto ray = [](glm::vec3 o, glm::vec3 d) {
    lsk::Ray r;
    r.origin = o;
    r.dir = glm::normalize(d);
    r.tmin = 0.0f;
    r.tmax = lsk::ls_infinity();
    return r;
  };
  const std::vector<lsk::Ray> rays = {
      ray({0.5f, 0.1f, 1e-4f}, {0.2f, 0.1f, 1.0f}),          // leaves the lower plane upwards: meets the upper one
      ray({0.4f, -0.2f, 1.0f - 1e-4f}, {-0.1f, 0.2f, -1.0f}), // leaves the upper plane downwards: meets the lower one
      ray({0.5f, 0.1f, 1.0f + 1e-4f}, {0.2f, 0.1f, 1.0f}),   // leaves the upper plane upwards: nothing ahead
      ray({0.3f, 0.3f, -1e-4f}, {0.1f, -0.1f, -1.0f}),       // leaves the lower plane downwards: nothing ahead
  };
  const Accel exact = build_accel(scene, parse_structure("bvh"), paper());
  const std::vector<lsk::Hit> want = trace_all(exact, rays);
  REQUIRE(want[0].triangle != lsk::LS_INVALID);
  REQUIRE(want[1].triangle != lsk::LS_INVALID);
  REQUIRE(want[2].triangle == lsk::LS_INVALID);
  REQUIRE(want[3].triangle == lsk::LS_INVALID);
  for (const char* name : {"f-ls:0:4", "f-ls:0:6", "2l-ls:0:5"}) {
    INFO(name);
    const Accel a = build_accel(scene, parse_structure(name), paper());
    REQUIRE(a.ls_info.ls_nodes == 1);
    for (size_t i = 0; i < rays.size(); ++i) {
      INFO("ray " << i);
      const std::vector<lsk::Ray> one = {rays[i]};
      lsk::LsCounters e{}, r{}, m{};
      const lsk::Hit got_exact = trace_all(a, one, false, &e, angle(45.0f))[0];
      const lsk::Hit got = trace_all(a, one, false, &r, angle(45.0f, LsBehind::Reverse))[0];
      const lsk::Hit got_empty = trace_all(a, one, false, &m, angle(45.0f, LsBehind::Empty))[0];
      REQUIRE(e.refused_behind == 1);  // every ray starts behind its shaft's first candidate
      REQUIRE(r.refused_behind == 0);
      REQUIRE(got_exact.t == want[i].t);  // refused: the subtree traversed exactly
      if (i < 2) {
        REQUIRE(r.accepted == 1);  // the reverse shaft's candidate is the plane ahead
        REQUIRE(got.triangle != lsk::LS_INVALID);
        REQUIRE(got.t == Approx(want[i].t).epsilon(1e-5));
        REQUIRE(m.refused_behind == 1);  // empty mode: a candidate ahead does not answer
        REQUIRE(got_empty.t == want[i].t);
      } else {
        REQUIRE(r.empty == 1);  // the reverse shaft's candidate is the plane the ray leaves
        REQUIRE(got.triangle == lsk::LS_INVALID);
        REQUIRE(m.empty == 1);
        REQUIRE(m.refused_behind == 0);
        REQUIRE(got_empty.triangle == lsk::LS_INVALID);
      }
    }
  }
}

TEST_CASE("behind the origin with --ls-behind reverse or empty, the lookup decides as documented, on a hand-made Line Space", "[line_space]") {
  // One LS box [-1, 1]^2 x [-1, 2], N = 4.  Shafts starting on the -Z face hold the plane z = 0 (L),
  // those starting on +Z the triangle U under test, every other shaft is empty.  The rays start just
  // above L, so their shaft's candidate L lies behind them and the reverse shaft's is U (or empty).
  const uint32_t n = 4;
  lsk::LsNode node{};
  node.lo = glm::vec3(-1.0f, -1.0f, -1.0f);
  node.hi = glm::vec3(1.0f, 1.0f, 2.0f);
  node.scale = float(n) / (node.hi - node.lo);
  node.n = n;
  node.inv_n = 1.0f / float(n);
  node.bytes = 4;
  node.range_count = 2;
  std::vector<uint32_t> candidates(lsk::ls_shaft_count(n));
  for (uint32_t shaft = 0; shaft < candidates.size(); ++shaft) {
    uint32_t start, end;
    lsk::ls_shaft_patches(shaft, n, start, end);
    const uint32_t face = start / (n * n);
    candidates[shaft] = face == 4 ? 0u : face == 5 ? 1u : lsk::LS_INVALID;
  }
  auto plane = [](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    lsk::Triangle t;
    t.v0 = glm::vec4(a, 1.0f);
    t.v1 = glm::vec4(b, 1.0f);
    t.v2 = glm::vec4(c, 1.0f);
    return t;
  };
  auto horizontal = [&](float z) { return plane({-1, -1, z}, {3, -1, z}, {-1, 3, z}); };
  // A horizontal triangle whose east edge is the line x = east, the rays' plane hits east of it.
  auto west_of = [&](float east, float z) { return plane({-1, -1, z}, {east, -1, z}, {east, 3, z}); };
  const uint32_t up = 0u, along_x = 0x7fffu;  // octahedral codes of (0, 0, 1) and (1, 0, 0)
  const std::vector<uint32_t> ids = {0, 1}, instances = {0, 0};
  struct Case {
    const char* what;
    lsk::Triangle u;
    uint32_t u_normal;
    glm::vec3 dir;
    float current_t;
    float tmax;       // as launched
    uint32_t answer;  // with --ls-behind reverse
    uint32_t counter_offset;  // the LsCounters field it counts in
    bool empty_too = false;   // --ls-behind empty gives the same "empty" (else it refuses as behind)...
    float off_patches = 0.0f;  // ...where the plane hit lies at most --ls-leave-reach patches off U
  };
  using C = lsk::TraceContext;
  const glm::vec3 upwards(0.2f, 0.1f, 1.0f);
  const std::vector<Case> cases = {
      {"the plane ahead answers", horizontal(1.0f), up, upwards, kInf, kInf, C::LS_ACCEPTED, offsetof(lsk::LsCounters, accepted)},
      // Half a patch is half the line's chord through the box over N: 0.5 * 3 / 0.976 / 4 = 0.38.
      {"within half a patch ahead: the surface the ray leaves", horizontal(0.05f), up, upwards, kInf, kInf, C::LS_EMPTY,
       offsetof(lsk::LsCounters, empty), true},
      {"within half a patch behind: the surface the ray leaves", horizontal(-0.3f), up, upwards, kInf, kInf, C::LS_EMPTY,
       offsetof(lsk::LsCounters, empty), true},
      // The plane hit at z = 0.05 lies at x = 0.51; a patch is 0.77.
      {"0.13 patches outside its triangle: the surface the ray leaves, by default", west_of(0.41f, 0.05f), up, upwards,
       kInf, kInf, C::LS_EMPTY, offsetof(lsk::LsCounters, empty), true, 0.13f},
      {"0.39 patches outside its triangle: another surface of its plane, by default", west_of(0.21f, 0.05f), up, upwards,
       kInf, kInf, C::LS_EMPTY, offsetof(lsk::LsCounters, empty), true, 0.39f},
      {"farther behind: a surface the ray does not leave, which only reverse trusts", horizontal(-0.5f), up, upwards,
       kInf, kInf, C::LS_EMPTY, offsetof(lsk::LsCounters, empty)},
      {"past the box's exit: no surface in the box, which only reverse trusts", horizontal(5.0f), up, upwards, kInf, kInf,
       C::LS_EMPTY, offsetof(lsk::LsCounters, empty)},
      {"beyond the current hit: the answer all the same, which does not win", horizontal(1.0f), up, upwards, 0.5f, kInf,
       C::LS_ACCEPTED, offsetof(lsk::LsCounters, accepted)},
      {"beyond tmax as launched: refused", horizontal(1.0f), up, upwards, 0.5f, 0.5f, C::LS_FALLBACK,
       offsetof(lsk::LsCounters, refused_beyond)},
      {"past the refusal angle: refused", plane({0.8f, -1, -1}, {0.8f, 3, -1}, {0.8f, -1, 3}), along_x, upwards, kInf, kInf,
       C::LS_FALLBACK, offsetof(lsk::LsCounters, refused_angle)},
      {"an empty reverse shaft (it starts on +X)", horizontal(1.0f), up, glm::vec3(0.5f, 0.0f, 0.6f), kInf, kInf, C::LS_EMPTY,
       offsetof(lsk::LsCounters, empty), true},
  };
  const float reach = LsLookup{}.leave_reach;
  REQUIRE(reach == 0.25f);  // the cases' distances straddle it
  const std::pair<uint32_t, float> settings[] = {{C::LS_BEHIND_EXACT, reach},  {C::LS_BEHIND_REVERSE, reach},
                                                 {C::LS_BEHIND_EMPTY, reach},  {C::LS_BEHIND_EMPTY, 0.0f},
                                                 {C::LS_BEHIND_EMPTY, 0.5f},   {C::LS_BEHIND_EMPTY, kInf}};
  for (const Case& k : cases) {
    INFO(k.what);
    const std::vector<lsk::Triangle> tris = {horizontal(0.0f), k.u};
    const std::vector<lsk::LsRecord> records = {ls::make_ls_record(tris[0], glm::uvec3(up), 0u),
                                                ls::make_ls_record(tris[1], glm::uvec3(k.u_normal), 1u)};
    for (const auto& [behind, leave_reach] : settings) {
      INFO("behind " << behind << ", leave reach " << leave_reach);
      C c;
      c.tris = tris.data();
      c.tri_ids = ids.data();
      c.tri_instances = instances.data();
      c.ls_nodes = &node;
      c.ls_candidates = candidates.data();
      c.ls_records = records.data();
      c.ls_cos2 = 0.5f;  // 45 degrees
      c.ls_behind = behind;
      c.ls_leave_reach = leave_reach;
      const glm::vec3 origin(0.5f, 0.1f, 1e-4f), dir = glm::normalize(k.dir);
      lsk::Hit hit{};
      hit.t = k.current_t;
      hit.instance = hit.triangle = lsk::LS_INVALID;
      uint32_t prim = lsk::LS_INVALID;
      // The BVH node's box is the LS box here.
      const uint32_t answer =
          c.ls_lookup(0, node.lo, node.hi, origin, dir, lsk::safe_reciprocal(dir), 0.0f, k.tmax, lsk::LS_INVALID, hit, prim);
      uint32_t counted;
      std::memcpy(&counted, reinterpret_cast<const char*>(&c.ls_counters) + k.counter_offset, sizeof counted);
      // The documented default: behind the origin, refused; with empty, every answer but the "empty"
      // of an empty reverse shaft or of the surface the ray leaves.
      if (behind == C::LS_BEHIND_EXACT || (behind == C::LS_BEHIND_EMPTY && !(k.empty_too && k.off_patches <= leave_reach))) {
        CHECK(answer == C::LS_FALLBACK);
        CHECK(c.ls_counters.refused_behind == 1u);
        CHECK(c.ls_counters.lookups == 1u);
        CHECK(prim == lsk::LS_INVALID);
        continue;
      }
      CHECK(answer == k.answer);
      CHECK(counted == 1u);
      CHECK(c.ls_counters.lookups == 1u);
      CHECK(c.ls_counters.refused_behind == 0u);
      if (answer == C::LS_ACCEPTED && k.current_t < 1.0f) {  // not closer than the current hit: not offered
        CHECK(prim == lsk::LS_INVALID);
        CHECK(hit.triangle == lsk::LS_INVALID);
      } else if (answer == C::LS_ACCEPTED) {
        CHECK(prim == 1u);
        CHECK(hit.triangle == 1u);
        CHECK(hit.t == Approx((1.0f - 1e-4f) / dir.z).epsilon(1e-6));
      } else {
        CHECK(hit.triangle == lsk::LS_INVALID);
      }
    }
  }
}

TEST_CASE("the names of --ls-behind: each parses to its mode and back, the default first, and another name is refused naming them all", "[line_space]") {
  const std::vector<std::string> names = ls_behind_names();
  REQUIRE(names.size() == 3u);
  CHECK(names.front() == ls_behind_name(LsLookup{}.behind));
  std::set<int> modes;
  for (const std::string& name : names) {
    const LsBehind b = parse_ls_behind(name);
    CHECK(ls_behind_name(b) == name);
    modes.insert(int(b));
    LsLookup l;
    l.behind = b;
    modes.insert(100 + int(ls_behind_code(l)));  // distinct kernel codes too
  }
  CHECK(modes.size() == 2u * names.size());
  try {
    parse_ls_behind("sideways");
    FAIL("no InputError");
  } catch (const InputError& e) {
    const std::string what = e.what();
    CHECK(what.find("sideways") != std::string::npos);
    for (const std::string& name : names) CHECK(what.find(name) != std::string::npos);
  }
}

TEST_CASE("2L-LS stores one Line Space per unique mesh however many instances use it", "[line_space]") {
  std::vector<glm::mat4> many;
  for (int i = 0; i < 64; ++i)
    many.push_back(glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(float(i % 8) * 1.5f, float(i / 8) * 1.5f, 0.0f)),
                               0.1f * float(i), glm::vec3(0, 1, 0)));
  const Mesh mesh = unit_cube_soup(400, 21);
  const Scene one = single_mesh_scene(mesh), sixty_four = single_mesh_scene(mesh, many);
  const Accel a1 = build_accel(one, parse_structure("2l-ls:2:3"), paper()), a64 = build_accel(sixty_four, parse_structure("2l-ls:2:3"), paper());
  CHECK(a64.ls_info.ls_nodes == a1.ls_info.ls_nodes);
  CHECK(a64.ls_candidates == a1.ls_candidates);
  CHECK(a64.bytes_ls() == a1.bytes_ls());
  // The flat LS grows with the instances.
  CHECK(build_accel(sixty_four, parse_structure("f-ls:6:3"), paper()).ls_info.ls_nodes > a1.ls_info.ls_nodes);
}

TEST_CASE("compact and paper candidates give identical hits and compact is smaller", "[line_space]") {
  const Scene scene = single_mesh_scene(unit_cube_soup(3000, 13));
  AccelOptions paper_mode = paper();
  paper_mode.ls.paper_candidates = true;
  for (const char* name : {"f-ls:3:4", "2l-ls:1:3"}) {
    const Accel c = build_accel(scene, parse_structure(name), paper()), p = build_accel(scene, parse_structure(name), paper_mode);
    const std::vector<lsk::Ray> rays = random_rays(10000, 8);
    REQUIRE(same_bits(trace_all(c, rays), trace_all(p, rays)));
    CHECK(c.ls_info.candidate_bytes < p.ls_info.candidate_bytes);
    CHECK(p.ls_info.candidate_bytes == p.ls_info.candidate_bytes_paper);
    CHECK(c.ls_info.candidate_bytes == c.ls_info.candidate_bytes_compact);
  }
}

TEST_CASE("an over-budget Line Space is refused before it is built", "[line_space]") {
  const Scene scene = single_mesh_scene(unit_cube_soup(5000, 2));
  AccelOptions tight = paper();
  tight.limits.max_memory = 1 << 20;
  const auto start = std::chrono::steady_clock::now();
  REQUIRE_THROWS_AS(build_accel(scene, parse_structure("f-ls:4:64"), tight), InputError);
  REQUIRE_THROWS_AS(build_accel(scene, parse_structure("f-ls:8:64"), paper()), InputError);  // ~256 nodes x 2 GB
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 2.0);
}
