// The fast CPU path (cpu/fast_tracer.h: wide SIMD BVH, four-lane triangle filter) against the scalar
// reference kernels: every hit record bit for bit (t, u, v, ids) and the Line Space counters, for
// closest and any hit, on the built-in scenes and random ones, every structure, both widths.
#include "accel.h"
#include "load_scene.h"
#include "ray_generators.h"

#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cstring>
#include <limits>
#include <random>
#include <sstream>

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Rng {
  std::mt19937 gen;
  explicit Rng(uint32_t seed) : gen(seed) {}
  float range(float a, float b) { return std::uniform_real_distribution<float>(a, b)(gen); }
  glm::vec3 vec(float a, float b) { return glm::vec3(range(a, b), range(a, b), range(a, b)); }
};

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

// Runs both paths on the same rays and requires identical hit records and counters; returns the
// number of Line Space lookups.
size_t require_same(const ls::Accel& accel, const std::vector<lsk::Ray>& rays, bool any_hit, const std::string& what) {
  INFO(what << ", " << accel.spec.name() << ", " << accel.fast->width() << "-wide, " << (any_hit ? "any hit" : "closest hit"));
  std::vector<lsk::Hit> ref(rays.size()), fast(rays.size());
  lsk::LsCounters ref_counters{}, fast_counters{};
  ls::trace_rays(accel, rays.data(), ref.data(), rays.size(), any_hit, &ref_counters, ls::Traversal::Reference);
  ls::trace_rays(accel, rays.data(), fast.data(), rays.size(), any_hit, &fast_counters, ls::Traversal::Fast);
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
  if (accel.spec.line_space()) {
    INFO("reference counters: " << describe(ref_counters) << "\nfast counters:      " << describe(fast_counters));
    CHECK(std::memcmp(&ref_counters, &fast_counters, sizeof(lsk::LsCounters)) == 0);
  }
  return ref_counters.lookups;
}

ls::AccelOptions options(int width, float angle = 45.0f, uint32_t min_triangles = 0) {
  ls::AccelOptions o;
  o.wide_width = width;
  o.ls.angle_degrees = angle;
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
      REQUIRE(accel.fast->width() == width);
      size_t lookups = 0;
      for (const auto& [kind, rays] : sets) {
        lookups += require_same(accel, rays, kind == "shadow", name + ", " + kind + " rays");
        if (kind != "shadow") lookups += require_same(accel, rays, true, name + ", " + kind + " rays");
      }
      INFO(name << ", " << s);
      if (accel.spec.line_space() && accel.ls_info.ls_nodes > 0) CHECK(lookups > 0);  // the Line Space was exercised
    }
}

ls::Mesh make_mesh(std::vector<glm::vec3> positions, std::vector<glm::uvec3> triangles) {
  ls::Mesh m;
  m.positions = std::move(positions);
  m.triangles = std::move(triangles);
  m.normals.assign(m.positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  for (size_t t = 0; t < m.triangles.size(); ++t) {  // face normals as vertex normals (the LS extrapolates them)
    const glm::uvec3 i = m.triangles[t];
    const glm::vec3 n = glm::cross(m.positions[i.y] - m.positions[i.x], m.positions[i.z] - m.positions[i.x]);
    if (glm::length(n) > 0.0f) m.normals[i.x] = m.normals[i.y] = m.normals[i.z] = glm::normalize(n);
  }
  m.materials.assign(m.triangles.size(), 0u);
  return m;
}

ls::Mesh soup(size_t n, Rng& rng, float extent, float size) {
  std::vector<glm::vec3> p;
  std::vector<glm::uvec3> t;
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 c = rng.vec(-extent, extent);
    for (int k = 0; k < 3; ++k) p.push_back(c + rng.vec(-size, size));
    t.push_back(glm::uvec3(3 * i, 3 * i + 1, 3 * i + 2));
  }
  return make_mesh(p, t);
}

// Axis-aligned unit grid in z = 0: shared edges and vertices, and boxes flat in z.
ls::Mesh grid(int cells) {
  std::vector<glm::vec3> p;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) p.push_back(glm::vec3(float(i) / float(cells), float(j) / float(cells), 0.0f));
  const auto at = [&](int i, int j) { return uint32_t(j * (cells + 1) + i); };
  std::vector<glm::uvec3> t;
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return make_mesh(p, t);
}

ls::Scene random_scene(uint32_t seed) {
  Rng rng(seed);
  ls::Scene s;
  s.name = "random";
  s.materials.push_back(ls::Material{});
  s.meshes.push_back(soup(2000, rng, 1.0f, 0.15f));
  s.meshes.push_back(grid(16));
  s.meshes.push_back(soup(40, rng, 0.5f, 0.3f));
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

lsk::Ray ray(const glm::vec3& o, const glm::vec3& d, float tmin = 0.0f, float tmax = kInf) {
  lsk::Ray r;
  r.origin = o;
  r.tmin = tmin;
  r.dir = d;
  r.tmax = tmax;
  return r;
}

}  // namespace

TEST_CASE("wide BVH: same hits and Line Space counters as the reference on builtin:cornell", "[wide]") {
  check_scene(ls::load_scene("builtin:cornell"), "builtin:cornell", {"bvh", "2l-bvh", "f-ls:4:4", "f-ls:8:6", "2l-ls:2:4", "2l-ls:0:6"}, 4000);
}

TEST_CASE("wide BVH: same hits and Line Space counters as the reference on builtin:generated", "[wide]") {
  check_scene(ls::load_scene("builtin:generated:30000:12:5"), "builtin:generated:30000:12:5",
              {"bvh", "2l-bvh", "f-ls:8:4", "2l-ls:4:4"}, 3000);
}

TEST_CASE("wide BVH: same hits and Line Space counters as the reference on builtin:instances", "[wide]") {
  // Two-level only: the flat BVH over its 3.3 M world triangles would take most of a minute here.
  check_scene(ls::load_scene("builtin:instances"), "builtin:instances", {"2l-bvh", "2l-ls:4:3"}, 2000, {4}, "2l-bvh");
}

TEST_CASE("wide BVH: same hits and Line Space counters as the reference on random instanced scenes", "[wide]") {
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
        const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(4, angle, min_tris));
        CHECK(require_same(a, rays, false, "angle " + std::to_string(angle) + ", min triangles " + std::to_string(min_tris)) > 0);
      }
}

TEST_CASE("wide BVH: same answers for axis-parallel, grazing, boundary and degenerate rays", "[wide]") {
  const ls::Scene scene = random_scene(4);
  Rng rng(99);
  std::vector<lsk::Ray> rays;
  const glm::vec3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int i = 0; i < 3000; ++i) {
    const glm::vec3 o = rng.vec(-4.0f, 4.0f);
    glm::vec3 d = rng.vec(-1.0f, 1.0f);
    switch (i % 6) {
      case 0: d = axes[i / 6 % 6]; break;                                     // parallel to two slabs
      case 1: d[i / 6 % 3] = 0.0f; break;                                     // parallel to one slab
      case 2: d[i / 6 % 3] = 1e-30f; break;                                   // denormal-sized reciprocal
      case 3: rays.push_back(ray(o, d, 0.5f, 3.0f)); continue;                // an interval
      case 4: rays.push_back(ray(glm::vec3(o.x, o.y, 0.0f), d)); continue;    // origins in grid planes
      default: break;
    }
    rays.push_back(ray(o, d));
  }
  rays.push_back(ray(glm::vec3(0.0f), glm::vec3(0.0f)));                     // zero direction
  rays.push_back(ray(glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f), 2.0f, 1.0f));  // empty interval
  rays.push_back(ray(glm::vec3(0.0f), glm::vec3(1.0f, 0.2f, 0.1f), 0.0f, std::numeric_limits<float>::quiet_NaN()));
  for (int width : {4, 8})
    for (const char* s : {"bvh", "2l-bvh", "f-ls:4:3", "2l-ls:2:3"}) {
      const ls::Accel a = ls::build_accel(scene, ls::parse_structure(s), options(width));
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
  ls::AccelOptions o;
  o.traversal = ls::parse_traversal("reference");
  const ls::Accel ref = ls::build_accel(scene, ls::parse_structure("f-ls:4:3"), o);
  CHECK(ref.traversal == ls::Traversal::Reference);
  CHECK_THROWS_AS(ls::parse_traversal("simd"), ls::InputError);
  o.wide_width = 16;
  CHECK_THROWS_AS(ls::build_accel(scene, ls::parse_structure("bvh"), o), ls::InputError);
}
