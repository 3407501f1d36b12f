// Top-level-only updates of two-level structures (cpu/build/top_level_update.h): after posing a
// scene and updating its 2L-BVH and 2L-LS (refusal angle 0), a moved instance is hit exactly where its
// transformed geometry is — the same ids, the same bits of t and the same u and v (as numbers: the
// sign of a zero may differ) as a flat BVH built from scratch on the posed scene and as brute force
// over the posed triangles, with the fast and the reference traversals — while the object arrays keep
// their addresses and bytes and no Line Space is built.  The poses use transforms that are exact in
// float (dyadic translations, 180-degree turns, power-of-two scales), so that a flat and a two-level
// structure must agree bit for bit; general poses are checked against a two-level structure built
// from scratch on the posed scene.
#include "common/model/animation.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/line_space_builder.h"
#include "cpu/build/top_level_update.h"
#include "cpu/trace/fast_tracer.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <limits>
#include <random>
#include <sstream>

using namespace test_support;  // StdRng: the standard distributions

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kNone = lsk::LS_INVALID;

std::string describe(const lsk::Hit& h) {
  std::ostringstream s;
  s.precision(9);
  s << "t=" << h.t << " inst=" << h.instance << " tri=" << h.triangle << " u=" << h.u << " v=" << h.v;
  return s.str();
}

ls::Mesh grid_box() {  // the closed cube [-0.5, 0.5]^3
  std::vector<glm::vec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? 0.5f : -0.5f, i & 2 ? 0.5f : -0.5f, i & 4 ? 0.5f : -0.5f);
  const std::vector<glm::uvec3> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return make_mesh(p, t);
}

void add_channel(ls::Animation& a, uint32_t node, ls::AnimationPath path, ls::Interpolation interp, std::vector<float> times,
                 std::vector<glm::vec4> values) {
  ls::AnimationChannel c;
  c.node = node;
  c.path = path;
  c.interpolation = interp;
  c.times = std::move(times);
  c.values = std::move(values);
  a.channels.push_back(c);
}

// Instance 0: a static floor; 1..6: one 400-triangle soup; 7..9: one cube.  Each moving instance has a
// node with a LINEAR translation (dyadic keys), a STEP rotation (identity, 180 degrees about x, y or z,
// identity) and a STEP scale (1, then 2 or 1/2, then 1).  At t = 0.5 every moving instance is turned,
// scaled and moved, exactly.  `exact` = false: LINEAR rotations by arbitrary angles instead.
ls::Scene animated_scene(bool exact) {
  ls::Scene s;
  s.name = exact ? "exact animation" : "general animation";
  s.materials.push_back(ls::Material{});
  s.meshes.push_back(make_mesh({{-8, -4, -8}, {8, -4, -8}, {8, -4, 8}, {-8, -4, 8}}, {{0, 1, 2}, {0, 2, 3}}));
  s.meshes.push_back(lattice_soup(400, 7));
  s.meshes.push_back(grid_box());
  ls::Animation a;
  a.name = "test";
  StdRng rng(11);
  for (uint32_t i = 0; i < 10; ++i) {
    ls::Instance inst;
    inst.mesh = i == 0 ? 0u : i <= 6 ? 1u : 2u;
    s.instances.push_back(inst);
    ls::RigNode node;
    node.instance = int(i);
    if (i > 0) node.translation = glm::dvec3(rng.grid(5.0f, 4));
    s.rig.order.push_back(i);
    s.rig.nodes.push_back(node);
    if (i == 0) continue;
    const glm::vec3 from(node.translation), to = from + rng.grid(2.0f, 4);
    add_channel(a, i, ls::AnimationPath::Translation, ls::Interpolation::Linear, {0.0f, 1.0f}, {glm::vec4(from, 0), glm::vec4(to, 0)});
    glm::vec4 turn(0.0f);
    turn[int(i % 3)] = 1.0f;  // 180 degrees about x, y or z
    if (exact) {
      add_channel(a, i, ls::AnimationPath::Rotation, ls::Interpolation::Step, {0.0f, 0.25f, 0.75f}, {{0, 0, 0, 1}, turn, {0, 0, 0, 1}});
    } else {
      const glm::vec3 axis = glm::normalize(rng.grid(1.0f, 8) + glm::vec3(0.01f));
      const float angle = rng.range(0.5f, 2.5f);
      add_channel(a, i, ls::AnimationPath::Rotation, ls::Interpolation::Linear, {0.0f, 1.0f},
                  {{0, 0, 0, 1}, glm::vec4(axis * std::sin(0.5f * angle), std::cos(0.5f * angle))});
    }
    const float k = i % 2 ? 0.5f : 2.0f;
    add_channel(a, i, ls::AnimationPath::Scale, ls::Interpolation::Step, {0.0f, 0.4f, 0.9f}, {{1, 1, 1, 0}, {k, k, k, 0}, {1, 1, 1, 0}});
  }
  s.rig.animations.push_back(a);
  s.camera = ls::framing_camera(s);
  ls::pose_scene(s, 0.0);
  return s;
}

// Rays from grid points (so that carrying them into object space is exact) aimed into the boxes of the
// moving instances, and some in random directions.
std::vector<lsk::Ray> aimed_rays(const ls::Scene& s, size_t n, uint32_t seed) {
  StdRng rng(seed);
  std::vector<lsk::Ray> rays;
  for (size_t r = 0; r < n; ++r) {
    lsk::Ray ray;
    ray.origin = rng.grid(10.0f, 64);
    ray.tmin = 0.0f;
    ray.tmax = kInf;
    if (r % 8 == 7) {
      ray.dir = rng.grid(1.0f, 1024) + glm::vec3(1e-3f);
    } else {
      const ls::Instance& inst = s.instances[size_t(rng.integer(1, 9))];
      const glm::vec3 target = ls::transform_point(inst.object_to_world, rng.grid(0.6f, 256));
      ray.dir = target - ray.origin;
    }
    rays.push_back(ray);
  }
  return rays;
}

// Closest hit over every posed world triangle, ties to the lower (instance, triangle).
std::vector<lsk::Hit> brute_force(const ls::Scene& s, const std::vector<lsk::Ray>& rays) {
  std::vector<lsk::Hit> hits;
  for (const lsk::Ray& ray : rays) {
    lsk::Hit best;
    best.t = kInf;
    best.instance = best.triangle = kNone;
    best.u = best.v = 0.0f;
    const lsk::TriRay tr = lsk::make_tri_ray(ray.origin, ray.dir);
    for (uint32_t i = 0; i < s.instances.size(); ++i) {
      const ls::Mesh& m = s.meshes[s.instances[i].mesh];
      for (uint32_t t = 0; t < m.triangles.size(); ++t) {
        glm::vec3 p[3];
        for (int k = 0; k < 3; ++k) p[k] = ls::transform_point(s.instances[i].object_to_world, m.positions[m.triangles[t][k]]);
        float th, u, v;
        if (!lsk::ray_triangle(tr, ray.tmin, ray.tmax, p[0], p[1], p[2], th, u, v)) continue;
        if (best.triangle == kNone || th < best.t) best = lsk::Hit{th, i, t, u, v};
      }
    }
    hits.push_back(best);
  }
  return hits;
}

// Traced with a refusal angle of 0: a Line Space refuses every approximation and must equal the
// exact structure (exact_ls()).
std::vector<lsk::Hit> trace(const ls::Accel& a, const std::vector<lsk::Ray>& rays, ls::Traversal traversal, bool any_hit = false) {
  std::vector<lsk::Hit> hits(rays.size());
  ls::LsLookup refuse_all;
  refuse_all.angle_degrees = 0.0f;
  ls::trace_rays(a, refuse_all, rays.data(), hits.data(), rays.size(), any_hit, nullptr, traversal);
  return hits;
}

// Hits that differ in their ids or the bits of t, or in the values of u and v (the first in the
// message).  u and v are compared as numbers: on an edge one side may say -0 and the other +0 (a
// 180-degree turn negates the sheared coordinates, and x - y and -(y - x) differ in the sign of an
// exact zero); `bits` compares them bit for bit too.
size_t differences(const std::vector<lsk::Hit>& a, const std::vector<lsk::Hit>& b, std::string& first, bool bits = false) {
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const bool same = bits ? std::memcmp(&a[i], &b[i], sizeof(lsk::Hit)) == 0
                           : std::memcmp(&a[i].t, &b[i].t, sizeof(float)) == 0 && a[i].instance == b[i].instance &&
                                 a[i].triangle == b[i].triangle && a[i].u == b[i].u && a[i].v == b[i].v;
    if (!same && n++ == 0) first = "ray " + std::to_string(i) + ": " + describe(a[i]) + " vs " + describe(b[i]);
  }
  return n;
}

ls::AccelOptions exact_ls() {  // traced by trace() with a refusal angle of 0
  ls::AccelOptions o;
  o.ls.min_triangles = 0;
  return o;
}

// What must not change: the object level's arrays, where they are and what they hold.
struct ObjectSnapshot {
  std::vector<const void*> where;
  std::vector<std::vector<char>> bytes;
  const void* fast_objects = nullptr;
  uint64_t build_id = 0;
  double ls_seconds = 0.0;

  template <class T>
  void add(const std::vector<T>& v) {
    where.push_back(v.data());
    bytes.emplace_back(reinterpret_cast<const char*>(v.data()), reinterpret_cast<const char*>(v.data() + v.size()));
  }
  explicit ObjectSnapshot(const ls::Accel& a) {
    add(a.nodes);
    add(a.tris);
    add(a.tri_ids);
    add(a.object_roots);
    add(a.node_ls);
    add(a.ls_nodes);
    add(a.ls_candidates);
    add(a.ls_records);
    fast_objects = a.fast->object_part();
    build_id = a.build_id;
    ls_seconds = a.ls_info.seconds;
  }
  bool operator==(const ObjectSnapshot& o) const {
    return where == o.where && bytes == o.bytes && fast_objects == o.fast_objects && build_id == o.build_id &&
           ls_seconds == o.ls_seconds;
  }
};

}  // namespace

TEST_CASE("top-level update: moved instances are hit exactly where flat BVHs and brute force find them", "[animation]") {
  ls::Scene scene = animated_scene(true);
  ls::Accel two_bvh = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  ls::Accel two_ls = ls::build_accel(scene, ls::parse_structure("2l-ls:2:4"), exact_ls());
  REQUIRE(two_ls.ls_info.ls_nodes > 0);
  const ObjectSnapshot bvh_before(two_bvh), ls_before(two_ls);
  const size_t layouts = ls::line_space_layouts();

  ls::pose_scene(scene, 0.5);
  const std::vector<lsk::Ray> rays = aimed_rays(scene, 4000, 5);
  const std::vector<lsk::Hit> stale = trace(two_bvh, rays, ls::Traversal::Fast);  // still the rest pose
  const ls::TopLevelUpdate u1 = ls::update_top_level(scene, two_bvh);
  const ls::TopLevelUpdate u2 = ls::update_top_level(scene, two_ls);
  CHECK(u1.top_nodes == two_bvh.top_nodes.size());
  CHECK(u2.seconds >= u2.wide_seconds);
  CHECK(two_bvh.top_level_version == 1);
  CHECK(ls::line_space_layouts() == layouts);  // no Line Space was built
  CHECK(ObjectSnapshot(two_bvh) == bvh_before);
  CHECK(ObjectSnapshot(two_ls) == ls_before);

  const ls::Accel flat = ls::build_accel(scene, ls::parse_structure("bvh"));
  const std::vector<lsk::Hit> brute = brute_force(scene, rays);
  const std::vector<lsk::Hit> flat_hits = trace(flat, rays, ls::Traversal::Fast);
  std::string first;
  const size_t flat_vs_brute = differences(flat_hits, brute, first);
  INFO("flat vs brute force: " << first);
  REQUIRE(flat_vs_brute == 0);
  size_t on_moved = 0, changed = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    on_moved += brute[i].triangle != kNone && brute[i].instance >= 1;
    changed += std::memcmp(&stale[i], &brute[i], sizeof(lsk::Hit)) != 0;
  }
  CHECK(on_moved > rays.size() / 2);  // the rays find the moved instances ...
  CHECK(changed > rays.size() / 2);   // ... where the rest pose's top level would not
  for (const ls::Accel* a : {&two_bvh, &two_ls})
    for (ls::Traversal traversal : {ls::Traversal::Fast, ls::Traversal::Reference}) {
      INFO(a->spec.name() << ", " << ls::traversal_name(traversal));
      const std::vector<lsk::Hit> got = trace(*a, rays, traversal);
      first.clear();
      const size_t vs_flat = differences(got, flat_hits, first);
      INFO("vs flat: " << first);
      CHECK(vs_flat == 0);
      first.clear();
      const size_t vs_brute = differences(got, brute, first);
      INFO("vs brute force: " << first);
      CHECK(vs_brute == 0);
      const std::vector<lsk::Hit> any = trace(*a, rays, traversal, true);
      size_t any_bad = 0;
      for (size_t i = 0; i < rays.size(); ++i) any_bad += (any[i].triangle == kNone) != (brute[i].triangle == kNone);
      CHECK(any_bad == 0);
    }
}

TEST_CASE("top-level update: a rebuilt top level is the one a full build of the posed scene makes", "[animation]") {
  ls::Scene scene = animated_scene(false);
  for (const char* name : {"2l-bvh", "2l-ls:2:4"}) {
    ls::Accel accel = ls::build_accel(scene, ls::parse_structure(name));
    for (double t : {0.3, 0.5, 0.77, 1.5}) {
      INFO(name << " at t = " << t);
      ls::pose_scene(scene, t);
      ls::update_top_level(scene, accel);
      const ls::Accel fresh = ls::build_accel(scene, ls::parse_structure(name));
      REQUIRE(accel.top_nodes.size() == fresh.top_nodes.size());
      REQUIRE(accel.instances.size() == fresh.instances.size());
      CHECK(std::memcmp(accel.top_nodes.data(), fresh.top_nodes.data(), fresh.top_nodes.size() * sizeof(lsk::BvhNode)) == 0);
      CHECK(std::memcmp(accel.instances.data(), fresh.instances.data(), fresh.instances.size() * sizeof(lsk::InstanceRecord)) == 0);
      const std::vector<lsk::Ray> rays = aimed_rays(scene, 1500, uint32_t(t * 100));
      std::string first;
      for (ls::Traversal traversal : {ls::Traversal::Fast, ls::Traversal::Reference}) {
        const size_t d = differences(trace(accel, rays, traversal), trace(fresh, rays, traversal), first, true);
        INFO(ls::traversal_name(traversal) << ": " << first);
        CHECK(d == 0);
      }
    }
  }
}

TEST_CASE("top-level update: a refitted top level gives the exact hits of a full build", "[animation]") {
  ls::Scene scene = animated_scene(false);
  ls::Accel refit_bvh = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  ls::Accel refit_ls = ls::build_accel(scene, ls::parse_structure("2l-ls:2:4"), exact_ls());
  const std::vector<lsk::BvhNode> rest_nodes = refit_bvh.top_nodes;
  ls::update_top_level(scene, refit_bvh, ls::TopLevelMode::Refit);  // same pose: the boxes the build made
  REQUIRE(refit_bvh.top_nodes.size() == rest_nodes.size());
  CHECK(std::memcmp(refit_bvh.top_nodes.data(), rest_nodes.data(), rest_nodes.size() * sizeof(lsk::BvhNode)) == 0);
  for (double t : {0.25, 0.6, 1.0}) {
    INFO("t = " << t);
    ls::pose_scene(scene, t);
    ls::update_top_level(scene, refit_bvh, ls::TopLevelMode::Refit);
    ls::update_top_level(scene, refit_ls, ls::TopLevelMode::Refit);
    CHECK(refit_bvh.top_nodes.size() == rest_nodes.size());  // the old tree, new boxes
    const ls::Accel fresh = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
    const std::vector<lsk::Ray> rays = aimed_rays(scene, 1500, uint32_t(t * 1000));
    const std::vector<lsk::Hit> want = trace(fresh, rays, ls::Traversal::Reference);
    std::string first;
    for (const ls::Accel* a : {&refit_bvh, &refit_ls})
      for (ls::Traversal traversal : {ls::Traversal::Fast, ls::Traversal::Reference}) {
        const size_t d = differences(trace(*a, rays, traversal), want, first, true);
        INFO(a->spec.name() << " " << ls::traversal_name(traversal) << ": " << first);
        CHECK(d == 0);
      }
  }
}

TEST_CASE("top-level update: builtin:carousel over its frames equals full two-level builds", "[animation]") {
  ls::Scene scene = ls::load_scene("builtin:carousel");
  ls::Accel accel = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  const ObjectSnapshot before(accel);
  for (int f : {1, 7, 30, 61}) {
    INFO("frame " << f);
    ls::pose_scene(scene, f / 24.0);
    ls::update_top_level(scene, accel);
    const ls::Accel fresh = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
    CHECK(std::memcmp(accel.top_nodes.data(), fresh.top_nodes.data(), fresh.top_nodes.size() * sizeof(lsk::BvhNode)) == 0);
    CHECK(std::memcmp(accel.instances.data(), fresh.instances.data(), fresh.instances.size() * sizeof(lsk::InstanceRecord)) == 0);
  }
  CHECK(ObjectSnapshot(accel) == before);
}

TEST_CASE("top-level update: flat structures and mismatched scenes are refused", "[animation]") {
  ls::Scene scene = animated_scene(true);
  ls::Accel flat = ls::build_accel(scene, ls::parse_structure("bvh"));
  CHECK_THROWS_AS(ls::update_top_level(scene, flat), ls::InputError);
  ls::Accel two = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  ls::Scene fewer = scene;
  fewer.instances.pop_back();
  CHECK_THROWS_AS(ls::update_top_level(fewer, two), ls::InputError);
  ls::Scene other = scene;
  other.instances[3].mesh = 2;
  CHECK_THROWS_AS(ls::update_top_level(other, two), ls::InputError);
  CHECK(ls::parse_top_level_mode("refit") == ls::TopLevelMode::Refit);
  CHECK_THROWS_AS(ls::parse_top_level_mode("rebuilt"), ls::InputError);
}
