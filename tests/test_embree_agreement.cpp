// Embree 3 is the correctness peer (docs/design.md §7): on the same rays, our exact structures (F-BVH and
// 2L-BVH) and Embree (robust mode, world-space triangles) must find the same closest triangle, at the
// same distance (t_close below), with the same barycentrics, and agree on occlusion.  Per scene and
// structure, with >= 100,000 rays:
//   - (instance, triangle) and hit/miss agree on >= 99.99 % of the rays;
//   - true disagreements (hit vs miss, or other triangle at another t) on <= 0.01 %; other triangle
//     at the same t is a tie (a shared edge: we pick the lower id, Embree any);
//   - same triangle: t agrees on every ray, u and v within 1e-3 on >= 99.9 %;
//   - any-hit on finite segments (t/2, 2t, shadow-like): occluded-or-not agrees on >= 99.99 %.
// Counts print as lines starting with "[embree]"; failing rays print in hex for a repro.
#include "common/render/surface.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/trace/embree_tracer.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <tiny_gltf.h>
#include <unistd.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace test_support;  // StdRng: the standard distributions

namespace {

constexpr size_t kRays = 100000;
constexpr double kRelT = 1e-5;   // relative tolerance on t (see t_close)
constexpr double kUv = 1e-3;     // absolute tolerance on u, v (same quantity, different formulas)
constexpr float kInf = std::numeric_limits<float>::infinity();

bool is_hit(const lsk::Hit& h) { return h.triangle != lsk::LS_INVALID; }

// t agrees when |a - b| <= 1e-5 * max(|a|, |b|, s) / c, where
//  - s = max|origin| / |dir|: never finer than 1e-5 of the coordinates' magnitude.  A hit at t = 1e-5
//    from an origin at 5 (a diffuse ray meeting an intersecting triangle) cannot be known to 1e-5 of t
//    on either side: rounding the world vertices (Embree, F-BVH) or the world-to-object transform
//    (2L-BVH) moves the surface by ~1e-7 of the coordinates;
//  - c = max(|cos|, 1e-3), cos the angle between the ray and the triangle's normal: a surface moved by
//    delta moves a grazing hit by delta / |cos|.  c = 1 where no triangle is given (ids differ).
float t_scale(const lsk::Ray& r) {
  const float o = std::max(std::max(std::fabs(r.origin.x), std::fabs(r.origin.y)), std::fabs(r.origin.z));
  const float d = glm::length(r.dir);
  return d > 0.0f ? o / d : 0.0f;
}

bool t_close(float a, float b, float scale, double cosine = 1.0) {
  if (a == b) return true;  // both +inf included
  if (!std::isfinite(a) || !std::isfinite(b)) return false;
  const double ref = std::max({std::fabs(double(a)), std::fabs(double(b)), double(scale)});
  return std::fabs(double(a) - double(b)) * std::max(std::fabs(cosine), 1e-3) <= kRelT * ref;
}

// |cos| of the angle between a ray and a triangle's normal (world space, in double).
double hit_cosine(const ls::SurfaceLookup& surfaces, const lsk::Ray& ray, const lsk::Hit& hit) {
  glm::vec3 p0, p1, p2;
  surfaces.world_triangle(hit.instance, hit.triangle, p0, p1, p2);
  const glm::dvec3 n = glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0));
  const glm::dvec3 d(ray.dir);
  const double len = glm::length(n) * glm::length(d);
  return len > 0.0 ? std::fabs(glm::dot(n, d)) / len : 0.0;
}

std::string describe(const lsk::Ray& r) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "ray{o=(%a, %a, %a) tmin=%a d=(%a, %a, %a) tmax=%a} = {o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) tmax=%.9g}",
                r.origin.x, r.origin.y, r.origin.z, r.tmin, r.dir.x, r.dir.y, r.dir.z, r.tmax, r.origin.x, r.origin.y,
                r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tmax);
  return buf;
}

std::string describe(const lsk::Hit& h) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "hit{t=%.9g inst=%d tri=%d u=%.6g v=%.6g}", h.t, int(h.instance), int(h.triangle), h.u, h.v);
  return buf;
}

struct ClosestCounts {
  size_t rays = 0;
  size_t hits = 0;           // rays our structure says hit
  size_t same_ids = 0;       // hit/miss and (instance, triangle) agree
  size_t ties = 0;           // ids differ, both hit, t within tolerance
  size_t disagreements = 0;  // hit vs miss, or ids and t both differ
  size_t t_mismatch = 0;     // ids agree, t differs beyond tolerance
  size_t uv_mismatch = 0;    // ids agree, u or v differ beyond kUv
  size_t bad_miss = 0;       // misses not reported as t = +inf with invalid ids
  double max_rel_t = 0.0;    // where ids agree: max |a - b| c / max(|a|, |b|, s), see t_close
};

ClosestCounts compare_closest(const ls::SurfaceLookup& surfaces, const std::vector<lsk::Ray>& rays,
                              const std::vector<lsk::Hit>& ours, const std::vector<lsk::Hit>& embree,
                              const std::string& label) {
  ClosestCounts c;
  c.rays = rays.size();
  int printed = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const lsk::Hit& a = ours[i];
    const lsk::Hit& b = embree[i];
    if (is_hit(a)) ++c.hits;
    // The miss convention (docs/design.md §9) holds on both sides.
    if (!is_hit(a) && !(a.t == kInf && a.instance == lsk::LS_INVALID)) ++c.bad_miss;
    if (!is_hit(b) && !(b.t == kInf && b.instance == lsk::LS_INVALID && b.u == 0.0f && b.v == 0.0f)) ++c.bad_miss;
    const bool same = is_hit(a) == is_hit(b) && a.instance == b.instance && a.triangle == b.triangle;
    if (same) {
      ++c.same_ids;
      if (is_hit(a)) {
        const double cosine = hit_cosine(surfaces, rays[i], a);
        if (!t_close(a.t, b.t, t_scale(rays[i]), cosine) && c.t_mismatch++ < 5)
          std::cout << "  t mismatch [" << label << "] ray " << i << " (|cos| " << cosine << "): " << describe(rays[i])
                    << "\n    ours " << describe(a) << "\n    embree " << describe(b) << "\n";
        const double ref = std::max({std::fabs(double(a.t)), std::fabs(double(b.t)), double(t_scale(rays[i]))});
        c.max_rel_t = std::max(c.max_rel_t, std::fabs(double(a.t) - double(b.t)) * std::max(cosine, 1e-3) / ref);
        if (std::fabs(a.u - b.u) > kUv || std::fabs(a.v - b.v) > kUv) ++c.uv_mismatch;
      }
      continue;
    }
    const bool tie = is_hit(a) && is_hit(b) && t_close(a.t, b.t, t_scale(rays[i]));
    if (tie) {
      ++c.ties;
    } else {
      ++c.disagreements;
      if (printed++ < 5)
        std::cout << "  disagreement [" << label << "] ray " << i << ": " << describe(rays[i]) << "\n    ours "
                  << describe(a) << "\n    embree " << describe(b) << "\n";
    }
  }
  return c;
}

// CHECK, not REQUIRE: a failing structure still lets the others run and print their numbers.
void check_closest(const ClosestCounts& c) {
  CHECK(c.rays > 0);
  CHECK(c.bad_miss == 0);
  CHECK(double(c.same_ids) >= 0.9999 * double(c.rays));       // ids agree on >= 99.99 % of the rays
  CHECK(double(c.disagreements) <= 1e-4 * double(c.rays));     // <= 0.01 % true disagreements
  CHECK(c.t_mismatch == 0);                                    // same triangle: same t (1e-5 relative)
  CHECK(double(c.uv_mismatch) <= 1e-3 * double(c.rays));
}

// Shadow-like segments with finite tmax, made from a closest-hit pass: for a ray hitting at t, the
// segments [0, t/2] (never occluded by the closest hit) and [0, 2t] (always occluded); and from each ray's
// origin towards another ray's hit point, with the unnormalised direction and tmax = 0.999 (a real
// shadow ray's shape, occluded or not).
std::vector<lsk::Ray> shadow_segments(const std::vector<lsk::Ray>& rays, const std::vector<lsk::Hit>& hits) {
  std::vector<lsk::Ray> out;
  std::vector<glm::vec3> points;
  for (size_t i = 0; i < rays.size(); ++i)
    if (is_hit(hits[i])) points.push_back(rays[i].origin + hits[i].t * rays[i].dir);
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!is_hit(hits[i])) continue;
    lsk::Ray r = rays[i];
    r.tmax = 0.5f * hits[i].t;
    out.push_back(r);
    r.tmax = 2.0f * hits[i].t;
    out.push_back(r);
  }
  if (!points.empty()) {
    for (size_t i = 0; i < rays.size(); ++i) {
      lsk::Ray r = rays[i];
      const glm::vec3 target = points[(i * 7919u + 13u) % points.size()];
      r.dir = target - r.origin;
      if (r.dir == glm::vec3(0.0f)) continue;
      r.tmax = 0.999f;
      out.push_back(r);
    }
  }
  return out;
}

struct AnyCounts {
  size_t rays = 0;
  size_t occluded = 0;        // by Embree
  size_t disagreements = 0;   // ours any-hit vs Embree occlusion
  size_t inconsistent = 0;    // ours any-hit vs ours closest hit within [tmin, tmax]
  size_t bad_convention = 0;  // Embree occlusion results not in the documented form
};

AnyCounts compare_any(const ls::Accel& accel, const ls::EmbreeTracer& embree, const std::vector<lsk::Ray>& rays,
                      const std::string& label) {
  std::vector<lsk::Hit> ours_any(rays.size()), ours_closest(rays.size()), theirs(rays.size());
  ls::trace_rays(accel, ls::LsLookup{}, rays.data(), ours_any.data(), rays.size(), true);
  ls::trace_rays(accel, ls::LsLookup{}, rays.data(), ours_closest.data(), rays.size(), false);
  embree.trace(rays.data(), theirs.data(), rays.size(), true);
  AnyCounts c;
  c.rays = rays.size();
  int printed = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const bool a = is_hit(ours_any[i]);
    const bool b = std::isfinite(theirs[i].t);
    // Embree's occlusion convention: t = tmin when occluded, +inf otherwise, never ids.
    if (theirs[i].instance != lsk::LS_INVALID || theirs[i].triangle != lsk::LS_INVALID ||
        (b && theirs[i].t != rays[i].tmin) || (!b && theirs[i].t != kInf))
      ++c.bad_convention;
    if (b) ++c.occluded;
    if (a != is_hit(ours_closest[i])) ++c.inconsistent;
    if (a != b) {
      ++c.disagreements;
      if (printed++ < 5)
        std::cout << "  any-hit disagreement [" << label << "] ray " << i << ": " << describe(rays[i]) << "\n    ours "
                  << describe(ours_any[i]) << " (closest " << describe(ours_closest[i]) << "), embree "
                  << (b ? "occluded" : "clear") << "\n";
    }
  }
  return c;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The whole comparison on one scene: Embree once, each exact structure once, the given ray sets traced
// closest-hit and as shadow segments (any-hit).
// isa: Embree's instruction set (embree_tracer.h).
void check_scene(const std::string& label, const ls::Scene& scene, const std::vector<ls::RayKind>& kinds, uint32_t seed,
                 const std::string& isa = "best") {
  auto start = std::chrono::steady_clock::now();
  const ls::EmbreeTracer embree(scene, isa);
  const double embree_total = seconds_since(start);
  const ls::SurfaceLookup surfaces(scene);
  std::cout << "[embree] " << label << ": " << ls::triangle_count(scene) << " triangles, " << scene.instances.size()
            << " instances; embree (" << embree.isa() << ") build " << embree.build_seconds() << " s (commit), " << embree_total
            << " s (total), " << double(embree.bytes()) / 1e6 << " MB\n";
  REQUIRE(embree.bytes() > 0);
  REQUIRE(embree.build_seconds() > 0.0);

  std::vector<ls::Accel> accels;
  for (const char* name : {"bvh", "2l-bvh"}) {
    start = std::chrono::steady_clock::now();
    accels.push_back(ls::build_accel(scene, ls::parse_structure(name)));
    std::cout << "[embree] " << label << ": built " << name << " in " << seconds_since(start) << " s\n";
  }

  for (ls::RayKind kind : kinds) {
    const char* kind_name = kind == ls::RayKind::Diffuse ? "diffuse" : kind == ls::RayKind::Random ? "random" : "primary";
    const std::vector<lsk::Ray> rays = ls::generate_rays(scene, accels[0], kind, kRays, seed);
    std::vector<lsk::Hit> theirs(rays.size());
    embree.trace(rays.data(), theirs.data(), rays.size(), false);
    for (const ls::Accel& accel : accels) {
      const std::string tag = label + " " + accel.spec.name() + " " + kind_name;
      INFO(tag);
      std::vector<lsk::Hit> ours(rays.size());
      ls::trace_rays(accel, ls::LsLookup{}, rays.data(), ours.data(), rays.size(), false);
      const ClosestCounts c = compare_closest(surfaces, rays, ours, theirs, tag);
      std::cout << "[embree] closest " << tag << ": rays " << c.rays << ", hits " << c.hits << ", same ids "
                << c.same_ids << ", ties " << c.ties << ", disagreements " << c.disagreements << " ("
                << 100.0 * double(c.disagreements) / double(c.rays) << " %), t mismatches " << c.t_mismatch
                << ", max rel t diff " << c.max_rel_t << ", uv mismatches " << c.uv_mismatch << "\n";
      check_closest(c);

      const std::vector<lsk::Ray> segments = shadow_segments(rays, ours);
      const AnyCounts a = compare_any(accel, embree, segments, tag);
      std::cout << "[embree] any-hit " << tag << ": segments " << a.rays << ", occluded " << a.occluded
                << ", disagreements " << a.disagreements << ", any-vs-closest inconsistencies " << a.inconsistent
                << "\n";
      CHECK(a.rays > 0);
      CHECK(a.bad_convention == 0);
      CHECK(double(a.disagreements) <= 1e-4 * double(a.rays));
      CHECK(double(a.inconsistent) <= 1e-4 * double(a.rays));
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// A random hand-built scene: a few meshes (closed bumpy spheres with shared edges, triangle soups, a flat
// grid), placed by instances with rotations, non-uniform and mirroring scales.

ls::Mesh bumpy_sphere(std::mt19937& rng, int rings, int segments) {
  std::uniform_real_distribution<float> noise(0.85f, 1.15f);
  ls::Mesh mesh;
  mesh.name = "bumpy sphere";
  const float pi = 3.14159265f;
  mesh.positions.push_back(glm::vec3(0.0f, 1.0f, 0.0f));
  for (int r = 1; r < rings; ++r) {
    const float theta = pi * float(r) / float(rings);
    for (int s = 0; s < segments; ++s) {
      const float phi = 2.0f * pi * float(s) / float(segments);
      mesh.positions.push_back(noise(rng) * glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta),
                                                      std::sin(theta) * std::sin(phi)));
    }
  }
  mesh.positions.push_back(glm::vec3(0.0f, -1.0f, 0.0f));
  const uint32_t south = uint32_t(mesh.positions.size() - 1);
  auto ring = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back(glm::uvec3(0, ring(1, s + 1), ring(1, s)));
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      mesh.triangles.push_back(glm::uvec3(ring(r, s), ring(r, s + 1), ring(r + 1, s + 1)));
      mesh.triangles.push_back(glm::uvec3(ring(r, s), ring(r + 1, s + 1), ring(r + 1, s)));
    }
  for (int s = 0; s < segments; ++s) mesh.triangles.push_back(glm::uvec3(south, ring(rings - 1, s), ring(rings - 1, s + 1)));
  return mesh;
}

ls::Mesh grid(int n) {
  ls::Mesh mesh;
  mesh.name = "grid";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      mesh.positions.push_back(glm::vec3(-1.0f + 2.0f * float(i) / float(n), 0.0f, -1.0f + 2.0f * float(j) / float(n)));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      mesh.triangles.push_back(glm::uvec3(a, b, d));
      mesh.triangles.push_back(glm::uvec3(a, d, c));
    }
  return mesh;
}

ls::Scene random_instanced_scene(uint32_t seed, int instances) {
  StdRng draws(seed);  // one generator for everything below, the soup's standard distributions included
  std::mt19937& rng = draws.gen;
  ls::Scene scene;
  scene.name = "random-instanced";
  scene.materials.push_back(ls::Material{});
  scene.meshes.push_back(bumpy_sphere(rng, 48, 96));
  scene.meshes.push_back(scattered_soup(draws, 3000, 1.0f, 0.25f, "soup"));
  scene.meshes.push_back(grid(32));
  scene.meshes.push_back(bumpy_sphere(rng, 12, 24));
  for (ls::Mesh& m : scene.meshes) finish_with_radial_normals(m);

  std::uniform_real_distribution<float> pos(-8.0f, 8.0f), scale(0.3f, 2.5f), angle(0.0f, 6.2831853f), unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> mesh_pick(0, int(scene.meshes.size()) - 1);
  for (int i = 0; i < instances; ++i) {
    ls::Instance inst;
    inst.mesh = uint32_t(mesh_pick(rng));
    glm::vec3 axis(unit(rng), unit(rng), unit(rng));
    if (glm::length(axis) < 1e-3f) axis = glm::vec3(0.0f, 1.0f, 0.0f);
    glm::vec3 s(scale(rng), scale(rng), scale(rng));
    if (i % 3 == 1) s.x = -s.x;                          // mirror: negative determinant
    if (i % 5 == 2) { s.y = -s.y; s.z = -s.z; }           // two flips: a rotation in disguise
    if (i % 7 == 3) s = -s;                              // point reflection: negative determinant
    glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(pos(rng), pos(rng), pos(rng)));
    m = glm::rotate(m, angle(rng), glm::normalize(axis));
    m = glm::scale(m, s);
    inst.object_to_world = m;
    inst.name = "instance " + std::to_string(i);
    scene.instances.push_back(inst);
  }
  ls::validate_scene(scene);
  scene.camera = ls::framing_camera(scene);
  return scene;
}

}  // namespace

TEST_CASE("embree tracer: ids, distances, barycentrics and conventions on two quads", "[embree]") {
  ls::Scene scene;
  scene.name = "two instances";
  scene.materials.push_back(ls::Material{});
  ls::Mesh mesh;
  mesh.positions = {glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f),
                    glm::vec3(1.0f, 1.0f, 0.0f)};
  mesh.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(1, 3, 2)};
  finish_with_radial_normals(mesh);
  scene.meshes.push_back(mesh);
  ls::Instance a;
  a.object_to_world = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, -2.0f));
  ls::Instance b;
  b.object_to_world = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, -4.0f)), glm::vec3(2.0f, 2.0f, -1.0f));
  scene.instances = {a, b};
  ls::validate_scene(scene);
  const ls::EmbreeTracer embree(scene);
  CHECK(embree.bytes() > 0);
  CHECK(embree.build_seconds() >= 0.0);

  std::vector<lsk::Ray> rays(5);
  // 0: hits instance 0, triangle 0 at t = 2, at the point (0.25, 0.5): u = 0.25, v = 0.5.
  rays[0] = {glm::vec3(0.25f, 0.5f, 0.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), kInf};
  // 1: misses instance 0 (outside its unit square) and hits instance 1 (scaled by 2), triangle 1.
  rays[1] = {glm::vec3(1.5f, 1.25f, 0.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), kInf};
  // 2: misses everything.
  rays[2] = {glm::vec3(5.0f, 5.0f, 0.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), kInf};
  // 3: interval ends before the first triangle: a miss.
  rays[3] = {glm::vec3(0.25f, 0.5f, 0.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), 1.5f};
  // 4: interval starts after the first triangle: hits instance 1 at t = 4; unnormalised direction.
  rays[4] = {glm::vec3(0.25f, 0.5f, 0.0f), 1.25f, glm::vec3(0.0f, 0.0f, -2.0f), kInf};
  std::vector<lsk::Hit> hits(rays.size());
  embree.trace(rays.data(), hits.data(), rays.size(), false);

  CHECK(hits[0].instance == 0u);
  CHECK(hits[0].triangle == 0u);
  CHECK(hits[0].t == Approx(2.0f).epsilon(1e-6));
  CHECK(hits[0].u == Approx(0.25f).margin(1e-6));
  CHECK(hits[0].v == Approx(0.5f).margin(1e-6));

  CHECK(hits[1].instance == 1u);
  CHECK(hits[1].t == Approx(4.0f).epsilon(1e-6));
  // World point (1.5, 1.25) is object point (0.75, 0.625), inside triangle 1 = (p1, p3, p2) =
  // ((1,0), (1,1), (0,1)) with weights w0 = 0.375, u = 0.375 (of p3), v = 0.25 (of p2).
  CHECK(hits[1].triangle == 1u);
  CHECK(hits[1].u == Approx(0.375f).margin(1e-6));
  CHECK(hits[1].v == Approx(0.25f).margin(1e-6));
  for (int i : {2, 3}) {
    CHECK(hits[i].t == kInf);
    CHECK(hits[i].instance == lsk::LS_INVALID);
    CHECK(hits[i].triangle == lsk::LS_INVALID);
    CHECK(hits[i].u == 0.0f);
    CHECK(hits[i].v == 0.0f);
  }
  CHECK(hits[4].instance == 1u);
  CHECK(hits[4].triangle == 0u);
  CHECK(hits[4].t == Approx(2.0f).epsilon(1e-6));

  // The same rays through our structures give the same answers.
  for (const char* name : {"bvh", "2l-bvh"}) {
    const ls::Accel accel = ls::build_accel(scene, ls::parse_structure(name));
    std::vector<lsk::Hit> ours(rays.size());
    ls::trace_rays(accel, ls::LsLookup{}, rays.data(), ours.data(), rays.size(), false);
    for (size_t i = 0; i < rays.size(); ++i) {
      INFO(name << " ray " << i);
      CHECK(ours[i].instance == hits[i].instance);
      CHECK(ours[i].triangle == hits[i].triangle);
      CHECK(t_close(ours[i].t, hits[i].t, t_scale(rays[i])));
    }
  }

  // Occlusion: t = tmin when occluded, +inf when clear; never ids.
  embree.trace(rays.data(), hits.data(), rays.size(), true);
  for (int i : {0, 1, 4}) {
    CHECK(hits[i].t == rays[i].tmin);
    CHECK(hits[i].instance == lsk::LS_INVALID);
    CHECK(hits[i].triangle == lsk::LS_INVALID);
  }
  for (int i : {2, 3}) CHECK(hits[i].t == kInf);
}

TEST_CASE("embree tracer: instances without triangles are skipped, ids kept", "[embree]") {
  // Instances of a mesh without triangles are skipped; ids of the others stay their instance ids.
  ls::Scene scene;
  scene.materials.push_back(ls::Material{});
  ls::Mesh empty;
  ls::Mesh tri;
  tri.positions = {glm::vec3(-1.0f, -1.0f, 0.0f), glm::vec3(1.0f, -1.0f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f)};
  tri.triangles = {glm::uvec3(0, 1, 2)};
  finish_with_radial_normals(tri);
  scene.meshes = {empty, tri};
  ls::Instance i0;
  i0.mesh = 0;
  ls::Instance i1;
  i1.mesh = 1;
  scene.instances = {i0, i1};
  const ls::EmbreeTracer embree(scene);
  lsk::Ray ray{glm::vec3(0.0f, 0.0f, 1.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), kInf};
  lsk::Hit hit;
  embree.trace(&ray, &hit, 1, false);
  CHECK(hit.instance == 1u);
  CHECK(hit.triangle == 0u);
  CHECK(hit.t == Approx(1.0f));
}

TEST_CASE("embree tracer: a memory limit cancels the build with the limit named, and is kept", "[embree]") {
  const ls::Scene scene = ls::load_scene("builtin:generated:20000:7:3");
  const ls::EmbreeTracer free_run(scene);
  const size_t needed = free_run.bytes();
  REQUIRE(needed > 100000);
  try {
    const ls::EmbreeTracer limited(scene, "best", needed / 2);  // less than the kept scene
    FAIL("the build under half its memory was not cancelled");
  } catch (const ls::EmbreeOverBudget& e) {
    CHECK(std::string(e.what()).find("Embree's scene would take more than") != std::string::npos);
    CHECK(std::string(e.what()).find("memory budget") != std::string::npos);
  }
  const ls::EmbreeTracer roomy(scene, "best", 64 * needed);  // room for the build's temporaries
  CHECK(roomy.bytes() > needed / 2);  // its parallel build need not keep the same bytes each time
  CHECK(roomy.bytes() <= 64 * needed);
}

TEST_CASE("embree agreement: builtin:cornell", "[embree]") {
  check_scene("builtin:cornell", ls::load_scene("builtin:cornell"), {ls::RayKind::Diffuse}, 1);
}

// bench --embree-isa sse2 compares the portable build with Embree's SSE2 kernels: they must answer as
// Embree's default ones do.
TEST_CASE("embree agreement: builtin:cornell with Embree limited to SSE2", "[embree]") {
  check_scene("builtin:cornell", ls::load_scene("builtin:cornell"), {ls::RayKind::Diffuse}, 1, "sse2");
}

TEST_CASE("embree instruction sets: names, this CPU's choice, limits and a refused name", "[embree]") {
  const std::vector<std::string>& names = ls::embree_isa_names();
  REQUIRE(names.front() == "best");
  const std::string best = ls::embree_effective_isa("best");
  const auto rank = [&](const std::string& isa) { return std::find(names.begin(), names.end(), isa) - names.begin(); };
  REQUIRE(rank(best) >= 1);
  REQUIRE(rank(best) < std::ptrdiff_t(names.size()));
  for (size_t i = 1; i < names.size(); ++i)  // a limit is kept where this CPU has it, else the CPU's best
    CHECK(ls::embree_effective_isa(names[i]) == (std::ptrdiff_t(i) <= rank(best) ? names[i] : best));
  CHECK(ls::embree_effective_isa("sse2") == "sse2");  // every x86-64 CPU has it
  CHECK_THROWS_AS(ls::embree_effective_isa("sse5"), ls::InputError);
  CHECK_THROWS_AS(ls::EmbreeTracer(ls::load_scene("builtin:cornell"), "avx3"), ls::InputError);
}

TEST_CASE("embree agreement: builtin:instances", "[embree]") {
  check_scene("builtin:instances", ls::load_scene("builtin:instances"), {ls::RayKind::Diffuse}, 2);
}

TEST_CASE("embree agreement: builtin:generated:200000:24:7", "[embree]") {
  check_scene("builtin:generated:200000:24:7", ls::load_scene("builtin:generated:200000:24:7"), {ls::RayKind::Diffuse}, 3);
}

TEST_CASE("embree agreement: instances with rotations, non-uniform and mirroring scales", "[embree]") {
  const ls::Scene scene = random_instanced_scene(12345u, 40);
  size_t mirrored = 0;
  for (const ls::Instance& inst : scene.instances)
    if (glm::determinant(glm::mat3(inst.object_to_world)) < 0.0f) ++mirrored;
  REQUIRE(mirrored > 0);
  REQUIRE(mirrored < scene.instances.size());
  check_scene("random-instanced", scene, {ls::RayKind::Diffuse, ls::RayKind::Random}, 4);
}

namespace {

// Writes a scene as a binary glTF the way an exporter would: one glTF mesh per object, the instances
// as child nodes (with matrices) of a parent node carrying a TRS transform.
void write_glb(const ls::Scene& scene, const std::string& path, const glm::vec3& parent_translation) {
  tinygltf::Model model;
  tinygltf::Buffer buffer;
  auto append = [&](const void* data, size_t bytes, int target) {
    while (buffer.data.size() % 4) buffer.data.push_back(0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.data.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    buffer.data.insert(buffer.data.end(), p, p + bytes);
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size()) - 1;
  };
  for (const ls::Mesh& mesh : scene.meshes) {
    tinygltf::Accessor pos, idx;
    pos.bufferView = append(mesh.positions.data(), mesh.positions.size() * 12, TINYGLTF_TARGET_ARRAY_BUFFER);
    pos.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    pos.type = TINYGLTF_TYPE_VEC3;
    pos.count = mesh.positions.size();
    ls::Bounds b;
    for (const glm::vec3& p : mesh.positions) b.grow(p);
    pos.minValues = {b.lo.x, b.lo.y, b.lo.z};
    pos.maxValues = {b.hi.x, b.hi.y, b.hi.z};
    model.accessors.push_back(pos);
    idx.bufferView = append(mesh.triangles.data(), mesh.triangles.size() * 12, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    idx.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    idx.type = TINYGLTF_TYPE_SCALAR;
    idx.count = mesh.triangles.size() * 3;
    model.accessors.push_back(idx);
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = int(model.accessors.size()) - 2;
    prim.indices = int(model.accessors.size()) - 1;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    tinygltf::Mesh m;
    m.primitives.push_back(prim);
    model.meshes.push_back(m);
  }
  model.buffers.push_back(buffer);
  tinygltf::Node parent;
  parent.translation = {parent_translation.x, parent_translation.y, parent_translation.z};
  for (const ls::Instance& inst : scene.instances) {
    tinygltf::Node node;
    node.mesh = int(inst.mesh);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) node.matrix.push_back(inst.object_to_world[c][r]);
    model.nodes.push_back(node);
    parent.children.push_back(int(model.nodes.size()) - 1);
  }
  model.nodes.push_back(parent);
  tinygltf::Scene root;
  root.nodes.push_back(int(model.nodes.size()) - 1);
  model.scenes.push_back(root);
  model.defaultScene = 0;
  model.asset.version = "2.0";
  tinygltf::TinyGLTF writer;
  REQUIRE(writer.WriteGltfSceneToFile(&model, path, false, true, false, true));
}

}  // namespace

TEST_CASE("embree agreement: a glTF file the loader has never seen", "[embree]") {
  // A generated scene of closed ellipsoids, each instance rotated, scaled (every third mirrored),
  // exported under a translated parent node, then read back through the glTF loader: hierarchy,
  // matrices, mirroring and file-order ids all go through the real path.
  ls::Scene source = ls::load_scene("builtin:generated:60000:12:9");
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> angle(0.0f, 6.2831853f), scale(0.5f, 1.5f);
  // The light quad (the last instance) stays put: turned about the world origin it would be a huge
  // plane that the shadow-like segments below meet at |cos| ~ 1e-4, where t is ill-conditioned.
  for (size_t i = 0; i + 1 < source.instances.size(); ++i) {
    glm::vec3 s(scale(rng), scale(rng), scale(rng));
    if (i % 3 == 1) s.x = -s.x;
    glm::mat4& m = source.instances[i].object_to_world;
    m = m * glm::scale(glm::rotate(glm::mat4(1.0f), angle(rng), glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f))), s);
  }
  const std::string path =
      (std::filesystem::temp_directory_path() / ("embree_unseen_" + std::to_string(getpid()) + ".glb")).string();
  write_glb(source, path, glm::vec3(0.5f, -1.25f, 2.0f));
  const ls::Scene loaded = ls::load_scene(path);
  std::filesystem::remove(path);
  REQUIRE(loaded.instances.size() == source.instances.size());
  REQUIRE(loaded.meshes.size() == source.meshes.size());
  check_scene("unseen.glb", loaded, {ls::RayKind::Diffuse, ls::RayKind::Random}, 6);
}
