// Scene loading: built-in scenes, glTF (written here, buffers embedded as base64 data URIs, and a
// hand-packed .glb), OBJ/OFF/PLY/STL, and every kind of bad input -> InputError.
#include "scenes/load_scene.h"
#include "tests/gltf_writer.h"

#include <catch2/catch.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <tuple>

namespace fs = std::filesystem;
using namespace ls;
using namespace ls_test;
using Catch::Matchers::Contains;

namespace {

// ---- files ----

// A fresh directory per test case, removed afterwards.
struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("linespace_test_scenes_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string write(const std::string& name, const std::string& content) const {
    const fs::path p = path / name;
    std::ofstream(p, std::ios::binary) << content;
    return p.string();
  }
};

// ---- checks ----

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_bits(const Scene& a, const Scene& b) {
  if (a.meshes.size() != b.meshes.size() || a.instances.size() != b.instances.size() ||
      a.materials.size() != b.materials.size() || a.name != b.name)
    return false;
  for (size_t i = 0; i < a.meshes.size(); ++i)
    if (!same_bits(a.meshes[i].positions, b.meshes[i].positions) || !same_bits(a.meshes[i].normals, b.meshes[i].normals) ||
        !same_bits(a.meshes[i].triangles, b.meshes[i].triangles) || !same_bits(a.meshes[i].materials, b.meshes[i].materials))
      return false;
  for (size_t i = 0; i < a.instances.size(); ++i)
    if (a.instances[i].mesh != b.instances[i].mesh ||
        std::memcmp(&a.instances[i].object_to_world, &b.instances[i].object_to_world, sizeof(glm::mat4)) != 0)
      return false;
  for (size_t i = 0; i < a.materials.size(); ++i)
    if (std::memcmp(&a.materials[i].albedo, &b.materials[i].albedo, sizeof(glm::vec3)) != 0 ||
        std::memcmp(&a.materials[i].emission, &b.materials[i].emission, sizeof(glm::vec3)) != 0)
      return false;
  return std::memcmp(&a.camera.position, &b.camera.position, sizeof(glm::vec3)) == 0 &&
         std::memcmp(&a.camera.target, &b.camera.target, sizeof(glm::vec3)) == 0 &&
         std::memcmp(&a.background, &b.background, sizeof(glm::vec3)) == 0;
}

bool near(const glm::vec3& a, const glm::vec3& b, float eps = 1e-5f) { return glm::length(a - b) <= eps; }

// Every normal is unit length and (unless the mesh is too sharp for smooth normals to follow its
// faces) agrees with the winding of the triangles that use it.
void check_normals(const Mesh& m, bool follow_winding = true) {
  INFO("mesh " << m.name);
  REQUIRE(m.normals.size() == m.positions.size());
  size_t not_unit = 0;
  for (const glm::vec3& n : m.normals) not_unit += !(std::fabs(glm::length(n) - 1.0f) < 1e-4f);
  CHECK(not_unit == 0);
  if (!follow_winding) return;
  size_t disagree = 0;
  for (const glm::uvec3& t : m.triangles) {
    const glm::vec3 face = glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
    if (glm::dot(face, m.normals[t.x] + m.normals[t.y] + m.normals[t.z]) <= 0.0f) ++disagree;
  }
  CHECK(disagree == 0);
}

using Key = std::tuple<float, float, float>;
Key key(const glm::vec3& p) { return {p.x, p.y, p.z}; }

// Closed and consistently wound: every directed edge (vertices compared by position) occurs exactly
// once and its reverse exactly once.  Returns the signed volume (positive: faces point outwards).
double closed_volume(const std::vector<glm::vec3>& pos, const std::vector<glm::uvec3>& tris) {
  std::map<std::pair<Key, Key>, int> directed;
  double volume = 0.0;
  for (const glm::uvec3& t : tris) {
    const glm::vec3 p[3] = {pos[t.x], pos[t.y], pos[t.z]};
    for (int e = 0; e < 3; ++e) ++directed[{key(p[e]), key(p[(e + 1) % 3])}];
    volume += glm::dot(glm::dvec3(p[0]), glm::cross(glm::dvec3(p[1]), glm::dvec3(p[2]))) / 6.0;
  }
  size_t bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    bad += count != 1 || reverse == directed.end() || reverse->second != 1;
  }
  CHECK(bad == 0);
  return volume;
}

std::vector<glm::vec3> world_positions(const Scene& s, const Instance& inst) {
  std::vector<glm::vec3> out;
  for (const glm::vec3& p : s.meshes[inst.mesh].positions) out.push_back(transform_point(inst.object_to_world, p));
  return out;
}

bool emissive(const Scene& s, const Mesh& m) {
  for (uint32_t mat : m.materials)
    if (glm::any(glm::greaterThan(s.materials[mat].emission, glm::vec3(0.0f)))) return true;
  return false;
}

bool inside(const glm::vec3& p, const Bounds& b) {
  return glm::all(glm::greaterThan(p, b.lo)) && glm::all(glm::lessThan(p, b.hi));
}

// Properties every built-in has: valid, unit normals agreeing with the winding, distinct materials,
// closed outward-facing solids, a closed inward-facing room when it has walls.  open_front (cornell):
// the room's walls and its lights, with a quad across the front, are closed; the camera is before it.
void check_builtin(const Scene& s, bool open_front = false) {
  REQUIRE_NOTHROW(validate_scene(s));
  for (const Mesh& m : s.meshes) check_normals(m);
  std::set<std::string> names;
  for (const Material& m : s.materials) names.insert(m.name);
  CHECK(names.size() == s.materials.size());
  std::vector<glm::vec3> wall_pos;
  std::vector<glm::uvec3> wall_tris;
  std::set<uint32_t> solids;
  for (const Instance& inst : s.instances) {
    const Mesh& m = s.meshes[inst.mesh];
    INFO("instance " << inst.name);
    const std::vector<glm::vec3> world = world_positions(s, inst);
    const bool closes_room = open_front && m.name.find("light") != std::string::npos;  // flush in the ceiling
    if (m.name.find("wall") != std::string::npos || m.name == "floor" || m.name == "ceiling" || closes_room) {
      for (const glm::uvec3& t : m.triangles) wall_tris.push_back(t + glm::uvec3(uint32_t(wall_pos.size())));
      wall_pos.insert(wall_pos.end(), world.begin(), world.end());
    } else if (m.name.find("light") == std::string::npos && m.name.find("blob") == std::string::npos) {
      // Solids face outwards: closed with positive volume in object space (each mesh once), and no
      // instance mirrors them.
      if (solids.insert(inst.mesh).second) CHECK(closed_volume(m.positions, m.triangles) > 0.0);
      CHECK(glm::determinant(glm::mat3(inst.object_to_world)) > 0.0f);
    }
  }
  if (!wall_tris.empty()) {
    Bounds room;
    for (const glm::vec3& p : wall_pos) room.grow(p);
    if (open_front) {  // a quad across z = max, facing into the room
      const uint32_t b = uint32_t(wall_pos.size());
      for (const glm::vec3& p : {glm::vec3(room.lo.x, room.lo.y, room.hi.z), glm::vec3(room.lo.x, room.hi.y, room.hi.z),
                                 glm::vec3(room.hi.x, room.hi.y, room.hi.z), glm::vec3(room.hi.x, room.lo.y, room.hi.z)})
        wall_pos.push_back(p);
      wall_tris.push_back({b, b + 1, b + 2});
      wall_tris.push_back({b, b + 2, b + 3});
    }
    CHECK(closed_volume(wall_pos, wall_tris) < 0.0);  // the room faces inwards
    if (open_front) {
      CHECK(s.camera.position.z > room.hi.z);
      CHECK(inside(glm::vec3(s.camera.position.x, s.camera.position.y, room.centre().z), room));
    } else {
      CHECK(inside(s.camera.position, room));
    }
    size_t outside = 0;  // everything is in the room
    for (const Instance& inst : s.instances)
      for (const glm::vec3& p : world_positions(s, inst))
        outside += !glm::all(glm::lessThanEqual(glm::abs(p - room.centre()), 0.5f * room.extent()));
    CHECK(outside == 0);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Built-in scenes

TEST_CASE("builtin:cornell is the classic box: open front, a flush light, both blocks and coloured walls in view", "[scenes]") {
  const Scene s = load_scene("builtin:cornell");
  CHECK(s.name == "builtin:cornell");
  CHECK(s.meshes.size() == 10);
  CHECK(s.instances.size() == 10);
  CHECK(triangle_count(s) < 10000);
  check_builtin(s, true);  // the walls and the light close the room but for its front
  size_t lights = 0, walls = 0;
  for (const Mesh& m : s.meshes) {
    if (emissive(s, m)) {
      ++lights;
      REQUIRE(m.triangles.size() == 2);
      for (const glm::vec3& p : m.positions) CHECK(p.y == 1.0f);      // flush with the ceiling ...
      for (const glm::vec3& n : m.normals) CHECK(n.y == Approx(-1)); // ... shining down
    }
    if (m.name.find("wall") != std::string::npos || m.name == "floor" || m.name == "ceiling") ++walls;
  }
  CHECK(lights == 1);
  CHECK(walls == 5);
  // A red left and a green right wall, as seen from the camera (at +z, looking down -z).
  for (const Mesh& m : s.meshes) {
    if (m.name == "left wall") CHECK(s.materials[m.materials[0]].albedo.r > s.materials[m.materials[0]].albedo.g);
    if (m.name == "right wall") CHECK(s.materials[m.materials[0]].albedo.g > s.materials[m.materials[0]].albedo.r);
  }
  // In view (square image): every vertex of both blocks, and the middle of both coloured walls.
  const glm::vec3 forward = glm::normalize(s.camera.target - s.camera.position);
  const glm::vec3 right = glm::normalize(glm::cross(forward, s.camera.up)), up = glm::cross(right, forward);
  const float half = std::tan(0.5f * s.camera.yfov);
  const auto in_view = [&](const glm::vec3& p) {
    const glm::vec3 d = p - s.camera.position;
    const float z = glm::dot(d, forward);
    return z > 0.0f && std::abs(glm::dot(d, right)) < half * z && std::abs(glm::dot(d, up)) < half * z;
  };
  size_t seen = 0;
  for (const Instance& inst : s.instances) {
    const std::string& name = s.meshes[inst.mesh].name;
    INFO(name);
    if (name == "tall box" || name == "short box") {
      for (const glm::vec3& p : world_positions(s, inst)) CHECK(in_view(p));
      ++seen;
    }
  }
  CHECK(seen == 2);
  CHECK(in_view({-1.0f, 0.0f, 0.0f}));
  CHECK(in_view({1.0f, 0.0f, 0.0f}));
}

TEST_CASE("builtin:instances has 64 instances of one 50k-triangle mesh inside a room", "[scenes]") {
  const Scene s = load_scene("builtin:instances");
  check_builtin(s);
  std::map<uint32_t, int> uses;
  for (const Instance& inst : s.instances) ++uses[inst.mesh];
  const auto most = std::max_element(uses.begin(), uses.end(), [](auto& a, auto& b) { return a.second < b.second; });
  CHECK(most->second >= 64);
  CHECK(s.meshes[most->first].triangles.size() >= 50000);
  CHECK(s.meshes.size() >= 8);  // plus walls, lights and unique objects
  size_t lights = 0, non_uniform = 0;
  for (const Mesh& m : s.meshes) lights += emissive(s, m);
  CHECK(lights >= 1);
  for (const Instance& inst : s.instances) {
    const glm::mat3 m(inst.object_to_world);
    if (std::fabs(glm::length(m[0]) - glm::length(m[1])) > 1e-3f) ++non_uniform;
  }
  CHECK(non_uniform > 0);
  CHECK(triangle_count(s) >= 64 * 50000);
}

TEST_CASE("builtin:generated hits its triangle and object counts", "[scenes]") {
  for (const auto& [spec, T, O] : std::vector<std::tuple<std::string, size_t, size_t>>{
           {"generated", 100000, 16}, {"generated:20000:10:3", 20000, 10}, {"generated:7:7:1", 7, 7},
           {"generated:5:1", 5, 1}, {"generated:7:1", 7, 1}, {"generated:1001:3:0", 1001, 3}}) {
    INFO(spec);
    const Scene s = load_scene("builtin:" + spec);
    check_builtin(s);
    CHECK(s.meshes.size() == O + 1);  // O objects and one light
    CHECK(s.instances.size() == O + 1);
    size_t tris = 0, lights = 0;
    for (const Instance& inst : s.instances) {
      if (emissive(s, s.meshes[inst.mesh])) ++lights;
      else tris += s.meshes[inst.mesh].triangles.size();
    }
    CHECK(lights == 1);
    CHECK(std::fabs(double(tris) - double(T)) <= 0.1 * double(T));
    CHECK(tris == T);  // exact, in fact
  }
  CHECK(!same_bits(load_scene("builtin:generated:3000:4:1"), load_scene("builtin:generated:3000:4:2")));
}

TEST_CASE("built-in scenes are deterministic", "[scenes]") {
  for (const std::string spec : {"builtin:cornell", "builtin:instances", "builtin:generated:50000:5:7"}) {
    INFO(spec);
    CHECK(same_bits(load_scene(spec), load_scene(spec)));
  }
}

TEST_CASE("bad built-in names and parameters are input errors", "[scenes]") {
  CHECK_THROWS_WITH(load_scene("builtin:nope"), Contains("cornell") && Contains("nope"));
  for (const std::string spec :
       {"generated:", "generated:abc", "generated:10:20", "generated:0", "generated:0:0", "generated:-5",
        "generated:+5", "generated: 100", "generated:1e5", "generated:100::1", "generated:1:2:3:4",
        "generated:60000000", "generated:100:1:x", "generated:99999999999999999999999", "generatedx", "",
        "generated:10:0"}) {
    INFO(spec);
    CHECK_THROWS_AS(load_scene("builtin:" + spec), InputError);
  }
}

TEST_CASE("scale_and_offset moves instances and camera together", "[scenes]") {
  const Scene before = load_scene("builtin:cornell");
  Scene s = before;
  const glm::vec3 offset(1000.0f, -5.0f, 2.0f);
  scale_and_offset(s, 2.0f, offset);
  REQUIRE_NOTHROW(validate_scene(s));
  for (size_t i = 0; i < s.instances.size(); ++i) {
    const glm::vec3 p = before.meshes[before.instances[i].mesh].positions[0];
    CHECK(near(transform_point(s.instances[i].object_to_world, p),
               2.0f * transform_point(before.instances[i].object_to_world, p) + offset, 1e-3f));
  }
  CHECK(near(s.camera.position, 2.0f * before.camera.position + offset, 1e-3f));
  CHECK(near(s.camera.target, 2.0f * before.camera.target + offset, 1e-3f));
  CHECK_THROWS_AS(scale_and_offset(s, 0.0f, offset), InputError);
  CHECK_THROWS_AS(scale_and_offset(s, std::nanf(""), offset), InputError);
}

// ---------------------------------------------------------------------------------------------------
// glTF

TEST_CASE("glTF node hierarchy: TRS and matrix transforms accumulate", "[scenes]") {
  TempDir dir;
  const float h = std::sqrt(0.5f);
  // node 0: translate (1,2,3) * rotate 90 deg about z * scale 2; its child node 1: matrix = translate (0,0,5).
  const std::string path = dir.write("tree.gltf", one_triangle_gltf(
      R"("nodes":[{"children":[1],"translation":[1,2,3],"rotation":[0,0,)" + std::to_string(h) + "," +
      std::to_string(h) + R"(],"scale":[2,2,2]},
      {"mesh":0,"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1]}],"scenes":[{"nodes":[0]}],"scene":0)"));
  const Scene s = load_scene(path);
  CHECK(s.name == path);
  REQUIRE(s.instances.size() == 1);
  REQUIRE(s.meshes.size() == 1);
  const glm::mat4& m = s.instances[0].object_to_world;
  CHECK(near(transform_point(m, {0, 0, 0}), {1, 2, 13}, 1e-4f));
  CHECK(near(transform_point(m, {1, 0, 0}), {1, 4, 13}, 1e-4f));  // x -> 2x -> rotated onto +y
  CHECK(near(transform_point(m, {0, 1, 0}), {-1, 2, 13}, 1e-4f));
  CHECK(s.background == glm::vec3(0.0f));
  // No camera in the file: a framing camera.
  const Camera framing = framing_camera(s);
  CHECK(near(s.camera.position, framing.position));
  CHECK(near(s.camera.target, framing.target));
}

TEST_CASE("glTF: two nodes instancing one mesh, ordered by node index", "[scenes]") {
  TempDir dir;
  // Scene 1 is the default.  Its roots are listed out of order (2 before 0); node 2's child is node 1;
  // node 3 is not reachable from the default scene.  Instances must follow node order: 0, 1, 2.
  Gltf g;
  const int pos = g.vec3(kTriangle);
  const std::string mesh = R"({"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) + "}}]}";
  const std::string path = dir.write("order.gltf", g.json(
      R"("meshes":[)" + mesh + "," + mesh + "," + mesh + R"(],
      "nodes":[{"mesh":0,"name":"n0","translation":[10,0,0]},{"mesh":1,"name":"n1"},
               {"mesh":2,"name":"n2","children":[1],"translation":[0,7,0]},{"mesh":0,"name":"n3"}],
      "scenes":[{"nodes":[3]},{"nodes":[2,0]}],"scene":1)"));
  const Scene s = load_scene(path);
  REQUIRE(s.instances.size() == 3);
  CHECK(s.instances[0].name == "n0");
  CHECK(s.instances[1].name == "n1");
  CHECK(s.instances[2].name == "n2");
  CHECK(s.instances[0].mesh == 0);
  CHECK(s.instances[1].mesh == 1);
  CHECK(s.instances[2].mesh == 2);
  CHECK(near(transform_point(s.instances[1].object_to_world, {0, 0, 0}), {0, 7, 0}));  // inherits node 2

  const std::string twice = dir.write("twice.gltf", one_triangle_gltf(
      R"("nodes":[{"mesh":0},{"mesh":0,"translation":[0,0,-3]}],"scenes":[{"nodes":[0,1]}])"));
  const Scene t = load_scene(twice);
  CHECK(t.meshes.size() == 1);
  REQUIRE(t.instances.size() == 2);
  CHECK(t.instances[0].mesh == 0);
  CHECK(t.instances[1].mesh == 0);
  CHECK(near(transform_point(t.instances[1].object_to_world, {0, 0, 0}), {0, 0, -3}));

  // No scenes at all: every node that is nobody's child is a root.
  const std::string noscene = dir.write("noscene.gltf", one_triangle_gltf(
      R"("nodes":[{"children":[1]},{"mesh":0},{"mesh":0}])"));
  CHECK(load_scene(noscene).instances.size() == 2);
}

TEST_CASE("glTF materials, primitives, index types, strips, fans and normals", "[scenes]") {
  TempDir dir;
  Gltf g;
  const int pos = g.vec3(kTriangle);
  const int i8 = g.indices(std::vector<uint8_t>{0, 1, 2});
  const int i16 = g.indices(std::vector<uint16_t>{0, 1, 2});
  const int i32 = g.indices(std::vector<uint32_t>{0, 1, 2});
  const int nrm = g.vec3({{0, 0, 2}, {0, 0, 3}, {0, 0, 0}});  // not unit; the last one unusable
  const int quad = g.vec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}});  // strip order
  const int fan = g.vec3({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});   // fan order
  const auto prim = [&](int idx, const std::string& extra) {
    return R"({"attributes":{"POSITION":)" + std::to_string(pos) + "}" +
           (idx >= 0 ? R"(,"indices":)" + std::to_string(idx) : "") + extra + "}";
  };
  const std::string path = dir.write("materials.gltf", g.json(
      R"("materials":[{"name":"glow","pbrMetallicRoughness":{"baseColorFactor":[0.1,0.2,0.3,1]},
         "emissiveFactor":[1,0.5,0.25],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}}},
         {"name":"plain"}],
      "meshes":[{"primitives":[)" + prim(i8, R"(,"material":0)") + "," + prim(i16, R"(,"material":1)") + "," +
      prim(i32, "") + "," + prim(-1, R"(,"material":1)") + R"(]},
        {"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) + R"(,"NORMAL":)" + std::to_string(nrm) + R"(}},
                       {"attributes":{"POSITION":)" + std::to_string(quad) + R"(},"mode":5},
                       {"attributes":{"POSITION":)" + std::to_string(fan) + R"(},"mode":6}]}],
      "nodes":[{"mesh":0},{"mesh":1}],"scenes":[{"nodes":[0,1]}])"));
  const Scene s = load_scene(path);
  REQUIRE(s.materials.size() == 3);  // the file's two and the grey default
  CHECK(s.materials[0].name == "glow");
  CHECK(near(s.materials[0].albedo, {0.1f, 0.2f, 0.3f}));
  CHECK(near(s.materials[0].emission, {4.0f, 2.0f, 1.0f}));
  CHECK(near(s.materials[1].albedo, glm::vec3(1.0f)));  // glTF's default baseColorFactor
  CHECK(near(s.materials[1].emission, glm::vec3(0.0f)));
  CHECK(near(s.materials[2].albedo, glm::vec3(0.8f)));

  const Mesh& m0 = s.meshes[0];
  REQUIRE(m0.triangles.size() == 4);  // four primitives concatenated in file order
  CHECK(m0.positions.size() == 12);
  CHECK(m0.materials == std::vector<uint32_t>{0, 1, 2, 1});
  CHECK(m0.triangles[1] == glm::uvec3(3, 4, 5));
  CHECK(m0.triangles[3] == glm::uvec3(9, 10, 11));
  for (const glm::vec3& n : m0.normals) CHECK(near(n, {0, 0, 1}));  // computed from the winding

  const Mesh& m1 = s.meshes[1];
  REQUIRE(m1.triangles.size() == 1 + 2 + 2);
  CHECK(near(m1.normals[0], {0, 0, 1}));
  CHECK(near(m1.normals[1], {0, 0, 1}));
  CHECK(near(m1.normals[2], {0, 0, 1}));  // the zero normal replaced by a computed one
  CHECK(m1.triangles[1] == glm::uvec3(3, 4, 5));   // strip: (0 1 2), (1 3 2)
  CHECK(m1.triangles[2] == glm::uvec3(4, 6, 5));
  CHECK(m1.triangles[3] == glm::uvec3(8, 9, 7));   // fan: (1 2 0), (2 3 0)
  CHECK(m1.triangles[4] == glm::uvec3(9, 10, 7));
  for (const Mesh& m : s.meshes) check_normals(m);
}

TEST_CASE("glTF camera: the first perspective camera node in node order", "[scenes]") {
  TempDir dir;
  const float h = std::sqrt(0.5f);
  // Node 0: orthographic (skipped); node 2: perspective, at (0,1,5), turned 90 degrees about +y so it
  // looks down -x; node 3: another perspective camera (later in node order, ignored).
  const std::string path = dir.write("camera.gltf", one_triangle_gltf(
      R"("cameras":[{"type":"orthographic","orthographic":{"xmag":1,"ymag":1,"zfar":10,"znear":0.1}},
                    {"type":"perspective","perspective":{"yfov":0.5,"znear":0.1}},
                    {"type":"perspective","perspective":{"yfov":1.2,"znear":0.1}}],
      "nodes":[{"camera":0},{"mesh":0},{"camera":1,"translation":[0,1,5],"rotation":[0,)" + std::to_string(h) +
      ",0," + std::to_string(h) + R"(]},{"camera":2}],"scenes":[{"nodes":[3,0,1,2]}])"));
  const Scene s = load_scene(path);
  CHECK(near(s.camera.position, {0, 1, 5}, 1e-5f));
  CHECK(near(glm::normalize(s.camera.target - s.camera.position), {-1, 0, 0}, 1e-5f));
  CHECK(near(s.camera.up, {0, 1, 0}, 1e-5f));
  CHECK(s.camera.yfov == Approx(0.5f));
}

TEST_CASE("glTF binary (.glb) loads like the text form", "[scenes]") {
  TempDir dir;
  Gltf g;
  const int pos = g.vec3(kTriangle), idx = g.indices(std::vector<uint32_t>{0, 2, 1});
  const std::string rest = R"("meshes":[{"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) +
                           R"(},"indices":)" + std::to_string(idx) +
                           R"(}]}],"nodes":[{"mesh":0,"translation":[0,0,1]}],"scenes":[{"nodes":[0]}])";
  const Scene b = load_scene(dir.write("scene.glb", g.glb(rest)));
  const Scene t = load_scene(dir.write("scene.gltf", g.json(rest)));
  REQUIRE(b.instances.size() == 1);
  CHECK(b.meshes[0].positions == kTriangle);
  CHECK(b.meshes[0].triangles[0] == glm::uvec3(0, 2, 1));
  CHECK(near(b.meshes[0].normals[0], {0, 0, -1}));
  CHECK(b.instances[0].object_to_world == t.instances[0].object_to_world);
  CHECK(b.meshes[0].positions == t.meshes[0].positions);
  // An upper-case extension works too.
  CHECK(load_scene(dir.write("SCENE.GLB", g.glb(rest))).instances.size() == 1);
}

TEST_CASE("bad glTF input is an input error naming the file", "[scenes]") {
  TempDir dir;
  const auto fails = [&](const std::string& name, const std::string& content, const std::string& why) {
    INFO(name << ": " << why);
    const std::string path = dir.write(name, content);
    CHECK_THROWS_WITH(load_scene(path), Contains(path));
    CHECK_THROWS_AS(load_scene(path), InputError);
  };
  const std::string good = one_triangle_gltf(R"("nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}])");
  REQUIRE_NOTHROW(load_scene(dir.write("good.gltf", good)));

  fails("json.gltf", "{ \"asset\": ", "malformed JSON");
  fails("empty.gltf", "", "empty file");
  fails("garbage.glb", "this is not a binary glTF at all", "garbage .glb");
  {
    Gltf g;
    g.vec3(kTriangle);
    const std::string full = g.glb(R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}])");
    fails("truncated.glb", full.substr(0, full.size() / 2), "truncated .glb");
    fails("short.glb", full.substr(0, 10), "header only");
    // A BIN chunk longer than what is left, under a header whose length fits the file (tinygltf read
    // past the end of such a file: a fuzzer's find).
    std::string lying = full.substr(0, full.size() - 4);
    const uint32_t length = uint32_t(lying.size());
    std::memcpy(lying.data() + 8, &length, 4);
    fails("bin_past_end.glb", lying, "BIN chunk past the end");
    CHECK_THROWS_WITH(load_scene(dir.write("bin_past_end.glb", lying)), Contains("runs past the end"));
  }
  // Accessors and views that run past their buffer.
  const auto mesh_with = [](const std::string& accessors_views, const std::string& prim) {
    // 36 bytes: one triangle's positions.
    return R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,)" +
           base64(std::string(reinterpret_cast<const char*>(kTriangle.data()), 36)) + R"("}],)" + accessors_views +
           R"(,"meshes":[{"primitives":[)" + prim + R"(]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
  };
  fails("accessor.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}])", R"({"attributes":{"POSITION":0}})"),
        "accessor count past the view");
  fails("offset.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"byteOffset":4,"componentType":5126,"count":3,"type":"VEC3"}])", R"({"attributes":{"POSITION":0}})"),
        "accessor offset past the view");
  fails("view.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteOffset":12,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":1,"type":"VEC3"}])", R"({"attributes":{"POSITION":0}})"),
        "view past the buffer");
  fails("stride.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36,"byteStride":16}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}])", R"({"attributes":{"POSITION":0}})"),
        "stride makes the last element run past the view");
  fails("noaccessor.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}])", R"({"attributes":{"POSITION":7}})"),
        "missing accessor");
  fails("type.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":9,"type":"SCALAR"}])", R"({"attributes":{"POSITION":0}})"),
        "POSITION not VEC3");
  fails("points.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}])", R"({"attributes":{"POSITION":0},"mode":0})"),
        "POINTS primitive");
  fails("lines.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}])", R"({"attributes":{"POSITION":0},"mode":1})"),
        "LINES primitive");
  fails("material.gltf", mesh_with(R"("bufferViews":[{"buffer":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}])", R"({"attributes":{"POSITION":0},"material":3})"),
        "missing material");
  {
    Gltf g;
    const int pos = g.vec3(kTriangle), idx = g.indices(std::vector<uint16_t>{0, 1, 7});
    fails("index.gltf", g.json(R"("meshes":[{"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) +
                               R"(},"indices":)" + std::to_string(idx) + R"(}]}],"nodes":[{"mesh":0}])"),
          "index out of range");
  }
  {
    Gltf g;
    const int pos = g.vec3({{0, 0, 0}, {1, 0, 0}, {0, std::nanf(""), 0}});
    fails("nan.gltf", g.json(R"("meshes":[{"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) +
                             R"(}}]}],"nodes":[{"mesh":0}])"),
          "NaN vertex");
  }
  {
    Gltf g;
    const int pos = g.vec3({{0, 0, 0}, {1, 0, 0}});
    fails("zero.gltf", g.json(R"("meshes":[{"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) +
                              R"(},"mode":5}]}],"nodes":[{"mesh":0}])"),
          "zero triangles");
  }
  fails("nomesh.gltf", one_triangle_gltf(R"("nodes":[{"name":"empty"}],"scenes":[{"nodes":[0]}])"), "no instances");
  fails("cycle.gltf", one_triangle_gltf(R"("nodes":[{"children":[1]},{"mesh":0,"children":[0]}],"scenes":[{"nodes":[0]}])"),
        "cyclic nodes");
  fails("self.gltf", one_triangle_gltf(R"("nodes":[{"mesh":0,"children":[0]}],"scenes":[{"nodes":[0]}])"),
        "node is its own child");
  fails("twoparents.gltf", one_triangle_gltf(R"("nodes":[{"children":[2]},{"children":[2]},{"mesh":0}],"scenes":[{"nodes":[0,1]}])"),
        "node reached twice");
  fails("child.gltf", one_triangle_gltf(R"("nodes":[{"mesh":0,"children":[5]}],"scenes":[{"nodes":[0]}])"),
        "missing child");
  fails("meshindex.gltf", one_triangle_gltf(R"("nodes":[{"mesh":4}],"scenes":[{"nodes":[0]}])"), "missing mesh");
  fails("projective.gltf", one_triangle_gltf(R"("nodes":[{"mesh":0,"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0.5, 0,0,0,1]}],"scenes":[{"nodes":[0]}])"),
        "projective matrix");
  fails("singular.gltf", one_triangle_gltf(R"("nodes":[{"mesh":0,"scale":[1,0,1]}],"scenes":[{"nodes":[0]}])"),
        "singular transform");
  {
    std::string nodes = R"("nodes":[)";
    for (int i = 0; i < 1100; ++i) nodes += R"({"children":[)" + std::to_string(i + 1) + "]},";
    nodes += R"({"mesh":0}],"scenes":[{"nodes":[0]}])";
    fails("deep.gltf", one_triangle_gltf(nodes), "hierarchy deeper than 1000");
  }
}

// ---------------------------------------------------------------------------------------------------
// OBJ / OFF / PLY / STL

TEST_CASE("mesh files: OFF, OBJ, PLY and STL load as one object", "[scenes]") {
  TempDir dir;
  const auto check = [](const Scene& s, size_t triangles) {
    REQUIRE(s.meshes.size() == 1);
    REQUIRE(s.instances.size() == 1);
    CHECK(s.instances[0].object_to_world == glm::mat4(1.0f));
    CHECK(s.meshes[0].triangles.size() == triangles);
    CHECK(s.materials.size() == 1);
    CHECK(s.background == glm::vec3(1.0f));
    check_normals(s.meshes[0]);
    const Camera framing = framing_camera(s);
    CHECK(near(s.camera.position, framing.position));
  };
  // A tetrahedron wound outwards.
  const Scene off = load_scene(dir.write("tet.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                                    "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"));
  check(off, 4);
  CHECK(closed_volume(off.meshes[0].positions, off.meshes[0].triangles) == Approx(1.0 / 6.0));

  // A quad (triangulated) with non-unit normals in the file.
  const std::string quad = "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 2\nvn 0 0 2\nvn 0 0 2\nvn 0 0 2\n"
                           "f 1//1 2//2 3//3 4//4\n";
  const Scene obj = load_scene(dir.write("quad.obj", quad));
  check(obj, 2);
  for (const glm::vec3& n : obj.meshes[0].normals) CHECK(near(n, {0, 0, 1}));
  check(load_scene(dir.write("QUAD.OBJ", quad)), 2);

  // A cube of quads in ASCII PLY.
  const Scene ply = load_scene(dir.write("cube.ply",
      "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
      "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n"));
  check(ply, 12);
  CHECK(closed_volume(ply.meshes[0].positions, ply.meshes[0].triangles) == Approx(1.0));

  // ASCII STL (its facet normals do not make vertex normals: computed).
  check(load_scene(dir.write("two.stl",
      "solid two\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n"
      "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid two\n")), 2);

  // Negative indices, v/t/n corners and a pentagon (fan-triangulated in order); normals from vn.
  const Scene penta = load_scene(dir.write("penta.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\nvt 0 0\n"
                                                        "vn 0 0 1\no thing\ng group\nusemtl none\n"
                                                        "f -5/1/1 -4/1/1 -3/1/1 -2/1/1 -1/1/1\n"));
  check(penta, 3);
  CHECK(penta.meshes[0].triangles[1] == glm::uvec3(0, 2, 3));
  CHECK(penta.meshes[0].triangles[2] == glm::uvec3(0, 3, 4));
  CHECK(near(penta.meshes[0].positions[3], {0.5f, 1.5f, 0.0f}));

  // NOFF: a triangle with its normals (scaled; made unit).
  const Scene noff = load_scene(dir.write("tri.off", "NOFF\n3 1 0\n0 0 0 0 0 3\n1 0 0 0 0 3\n0 1 0 0 0 3\n3 0 1 2\n"));
  check(noff, 1);
  CHECK(near(noff.meshes[0].normals[0], {0, 0, 1}));

  // Binary PLY, both byte orders, with normals and extra properties to skip.
  for (const bool big : {false, true}) {
    std::string ply = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\ncomment made by a test\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nproperty uchar red\nproperty float nx\nproperty float ny\nproperty float nz\n"
                      "element face 1\nproperty list uchar int vertex_indices\nproperty short flags\nend_header\n";
    const auto put = [&](const void* p, size_t n) {
      std::string b(static_cast<const char*>(p), n);
      if (big) std::reverse(b.begin(), b.end());
      ply += b;
    };
    const float xyz[3][3] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}};
    for (const auto& v : xyz) {
      for (float c : v) put(&c, 4);
      ply += char(200);
      const float n[3] = {-2, 0, 0};
      for (float c : n) put(&c, 4);
    }
    ply += char(3);
    for (int32_t i : {0, 1, 2}) put(&i, 4);
    const int16_t flags = 7;
    put(&flags, 2);
    const Scene s = load_scene(dir.write(big ? "be.ply" : "le.ply", ply));
    check(s, 1);
    CHECK(near(s.meshes[0].positions[1], {0, 0, 1}));
    CHECK(near(s.meshes[0].normals[2], {-1, 0, 0}));
    CHECK_THROWS_AS(load_scene(dir.write("cut.ply", ply.substr(0, ply.size() - 3))), InputError);
  }

  // Binary STL: 80-byte header, count, then 50 bytes per facet.
  std::string stl(80, ' ');
  const uint32_t one = 1;
  stl.append(reinterpret_cast<const char*>(&one), 4);
  const float facet[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
  stl.append(reinterpret_cast<const char*>(facet), sizeof(facet));
  stl.append(2, '\0');
  check(load_scene(dir.write("one.stl", stl)), 1);
}

TEST_CASE("bad mesh files and scene paths are input errors", "[scenes]") {
  TempDir dir;
  const auto fails = [&](const std::string& path, const std::string& why) {
    INFO(path << ": " << why);
    CHECK_THROWS_WITH(load_scene(path), Contains(path));
    CHECK_THROWS_AS(load_scene(path), InputError);
  };
  fails((dir.path / "missing.obj").string(), "missing file");
  fails((dir.path / "missing.gltf").string(), "missing file");
  fails(dir.write("scene.xyz", "solid\n"), "unknown extension");
  fails(dir.write("noextension", "OFF\n"), "no extension");
  fs::create_directories(dir.path / "dir.obj");
  fails((dir.path / "dir.obj").string(), "a directory");
  fails(dir.write("empty.obj", ""), "empty OBJ");
  fails(dir.write("vertices.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no faces");
  fails(dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n"), "NaN vertex");
  fails(dir.write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n"), "vertex beyond float range");
  fails(dir.write("short.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n"), "vertex with two coordinates");
  fails(dir.write("nan.off", "OFF\n4 2 0\n0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n"), "NaN vertex in OFF");
  fails(dir.write("nan.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex nan 1 0\n"
                             "endloop\nendfacet\nendsolid x\n"), "NaN vertex in STL");
  fails(dir.write("garbage.ply", "ply\nthis is not a ply file\n"), "garbage PLY");
  // Inputs on which OpenMesh 9's readers corrupt the heap, crash or never return.
  fails(dir.write("plus.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/1 +/1/1 4/1/1\n"),
        "bad face corner");
  fails(dir.write("typo.ply", "ply\nformat ascii 1.0\nelement ertex 4\nproperty float x\n[roperty float y\nend_hea2er\n"),
        "misspelt PLY header");
  fails(dir.write("typo2.ply", "ply\nfoemat binary_little_endian 1.0\nelement vertex 3\nproperty flat x\nend_header\n"),
        "misspelt PLY header");
  fails(dir.write("huge.ply", "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
                              "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n"),
        "vertex count far beyond the data");
  fails(dir.write("range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                               "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
        "PLY face index out of range");
  fails(dir.write("short.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n"), "OFF ends early");
  fails(dir.write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "OFF face index out of range");
  fails(dir.write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "OBJ face index out of range");
  fails(dir.write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "OBJ index 0");
  fails(dir.write("junk.stl", std::string(200, 'x')), "neither ASCII nor binary STL");
  {
    // Binary STL with a NaN coordinate: read as is, refused by validation.
    std::string stl(80, ' ');
    const uint32_t one = 1;
    stl.append(reinterpret_cast<const char*>(&one), 4);
    const float facet[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, std::nanf(""), 1, 0};
    stl.append(reinterpret_cast<const char*>(facet), sizeof(facet));
    stl.append(2, '\0');
    fails(dir.write("nan_binary.stl", stl), "NaN in binary STL");
  }
}
