// Rigid animation, loading and posing: glTF animation channels of translation, rotation and
// scale with each interpolation, posed at key times and between them as the glTF 2.0 specification
// (Appendix C) says — compared with matrices computed by hand here, not with the code's own output —
// hostile animation data refused with a one-line InputError, morph-target weights, several
// animations, and the built-in animated scene.
#include "common/model/animation.h"
#include "scenes/load_scene.h"
#include "tests/gltf_writer.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

using namespace ls_test;

namespace {

const std::string kMesh = R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}])";

// A file with the one-triangle mesh (accessors 0 and 1), `nodes`, and what `animations` adds (it may
// add accessors): the JSON of the "animations" array.
std::string file_with(const std::string& nodes, const std::function<std::string(Gltf&)>& animations,
                      const std::string& rest = R"("scenes":[{"nodes":[0]}])") {
  Gltf g;
  g.vec3(kTriangle);
  g.indices(std::vector<uint16_t>{0, 1, 2});
  const std::string anim = animations(g);
  return g.json(kMesh + R"(,"nodes":)" + nodes + (anim.empty() ? "" : R"(,"animations":)" + anim) + "," + rest);
}

std::vector<glm::vec4> v4(const std::vector<glm::vec3>& v) {
  std::vector<glm::vec4> out;
  for (const glm::vec3& x : v) out.emplace_back(x, 0.0f);
  return out;
}

// One animation with one channel on `node`.
std::function<std::string(Gltf&)> one_channel(std::vector<float> times, std::vector<glm::vec4> values,
                                              const std::string& interpolation = "LINEAR",
                                              const std::string& path = "translation", int node = 0) {
  return [=](Gltf& g) {
    const int in = g.scalars(times);
    const int out = path == "rotation" ? g.vec4(values) : g.vec3(std::vector<glm::vec3>(values.begin(), values.end()));
    return "[{\"channels\":[" + channel_json(0, node, path) + "],\"samplers\":[" + sampler_json(in, out, interpolation) + "]}]";
  };
}

ls::Scene load(const std::string& json) { return ls::load_gltf_bytes(json, "anim.gltf", false); }

// The posing test file (docs/design.md §9 ids: instances are nodes 1, 2, 3):
//   node 0 "rig": translation LINEAR (0,0,0) at 0 s -> (4,0,0) at 2 s; children 1, 2, 3
//   node 1: rest translation (0,1,0); rotation LINEAR from identity at 0 s to the NEGATED quaternion of
//           120 degrees about +z at 1 s (shortest path: the same rotation, reached the short way)
//   node 2: rest translation (5,0,0); scale STEP (1,1,1) at 0 s, (2,3,4) at 1 s
//   node 3: translation CUBICSPLINE, keys 0 s and 1 s: value (0,0,0) out-tangent (1,0,0); in-tangent
//           (0,2,0) value (1,1,0) (the unused tangents are 9s and 7s)
//   node 4: the camera, rest translation (0,0,5); translation LINEAR (0,0,5) -> (0,0,10) over 1 s
std::string posing_file() {
  const float s60 = 0.8660254037844386f, c60 = 0.5f;
  return file_with(
      R"([{"name":"rig","children":[1,2,3]},{"mesh":0,"translation":[0,1,0]},{"mesh":0,"translation":[5,0,0]},{"mesh":0},)"
      R"({"camera":0,"translation":[0,0,5]}])",
      [&](Gltf& g) {
        std::vector<std::string> channels, samplers;
        auto add = [&](int node, const std::string& path, const std::string& interp, std::vector<float> times,
                       std::vector<glm::vec4> values) {
          const int in = g.scalars(times);
          const int out = path == "rotation" ? g.vec4(values) : g.vec3(std::vector<glm::vec3>(values.begin(), values.end()));
          samplers.push_back(sampler_json(in, out, interp));
          channels.push_back(channel_json(int(samplers.size()) - 1, node, path));
        };
        add(0, "translation", "LINEAR", {0.0f, 2.0f}, v4({{0, 0, 0}, {4, 0, 0}}));
        add(1, "rotation", "LINEAR", {0.0f, 1.0f}, {{0, 0, 0, 1}, {0, 0, -s60, -c60}});
        add(2, "scale", "STEP", {0.0f, 1.0f}, v4({{1, 1, 1}, {2, 3, 4}}));
        add(3, "translation", "CUBICSPLINE", {0.0f, 1.0f}, v4({{9, 9, 9}, {0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {1, 1, 0}, {7, 7, 7}}));
        add(4, "translation", "LINEAR", {0.0f, 1.0f}, v4({{0, 0, 5}, {0, 0, 10}}));
        std::string a = "[{\"name\":\"posing\",\"channels\":[";
        for (size_t i = 0; i < channels.size(); ++i) a += (i ? "," : "") + channels[i];
        a += "],\"samplers\":[";
        for (size_t i = 0; i < samplers.size(); ++i) a += (i ? "," : "") + samplers[i];
        return a + "]}]";
      },
      R"("cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}],"scenes":[{"nodes":[0,4]}])");
}

// Column-major, as glm: columns x, y, z of the linear part and the translation.
glm::dmat4 columns(const glm::dvec3& x, const glm::dvec3& y, const glm::dvec3& z, const glm::dvec3& t) {
  return glm::dmat4(glm::dvec4(x, 0.0), glm::dvec4(y, 0.0), glm::dvec4(z, 0.0), glm::dvec4(t, 1.0));
}

// A rotation by the angle of (cos, sin) about +z, then the translation t.
glm::dmat4 rot_z(double c, double s, const glm::dvec3& t) { return columns({c, s, 0}, {-s, c, 0}, {0, 0, 1}, t); }

void check_matrix(const glm::mat4& got, const glm::dmat4& want, const char* what) {
  double err = 0.0;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) err = std::max(err, std::fabs(double(got[c][r]) - want[c][r]));
  INFO(what << ": max entry error " << err);
  CHECK(err < 2e-6);
}

void check_vec(const glm::vec3& got, const glm::dvec3& want, const char* what) {
  INFO(what << ": (" << got.x << ", " << got.y << ", " << got.z << ") vs (" << want.x << ", " << want.y << ", " << want.z << ")");
  CHECK(glm::length(glm::dvec3(got) - want) < 2e-6);
}

}  // namespace

TEST_CASE("glTF animation: the rest pose is the nodes' own TRS, not the animation's first keys", "[animation]") {
  const ls::Scene s = load(posing_file());
  REQUIRE(s.instances.size() == 3);
  REQUIRE(s.rig.animations.size() == 1);
  CHECK(s.rig.animations[0].channels.size() == 5);
  CHECK(s.rig.animations[0].duration() == 2.0);
  check_matrix(s.instances[0].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 1, 0}), "node 1 at rest");
  check_matrix(s.instances[1].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {5, 0, 0}), "node 2 at rest");
  check_vec(s.camera.position, {0, 0, 5}, "camera at rest");
}

TEST_CASE("glTF animation: LINEAR, slerp, STEP and CUBICSPLINE between keys", "[animation]") {
  ls::Scene s = load(posing_file());
  ls::pose_scene(s, 0.25);
  // rig (0.5,0,0); node 1: slerp a quarter of the way to 120 degrees is 30 degrees (a normalised lerp
  // would give 27.8); node 2 holds its first scale; node 3: Hermite at u = 0.25, h00 = 0.84375,
  // h10 = 0.140625, h01 = 0.15625, h11 = -0.046875: 0.140625 (1,0,0) + 0.15625 (1,1,0) - 0.046875 (0,2,0).
  check_matrix(s.instances[0].object_to_world, rot_z(0.8660254037844386, 0.5, {0.5, 1, 0}), "node 1 at 0.25 s");
  check_matrix(s.instances[1].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {5.5, 0, 0}), "node 2 at 0.25 s");
  check_matrix(s.instances[2].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.796875, 0.0625, 0}), "node 3 at 0.25 s");
  check_vec(s.camera.position, {0, 0, 6.25}, "camera at 0.25 s");
  check_vec(s.camera.target, {0, 0, 0}, "camera target at 0.25 s");  // looks down -z, 6.25 ahead
  check_vec(s.camera.up, {0, 1, 0}, "camera up");
  CHECK(s.camera.yfov == 0.8f);

  ls::pose_scene(s, 0.999);  // STEP still holds the first key just before the second (rig at 1.998)
  check_matrix(s.instances[1].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {6.998, 0, 0}), "node 2 at 0.999 s");
}

TEST_CASE("glTF animation: at key times and after the last key the keys' values hold", "[animation]") {
  ls::Scene s = load(posing_file());
  ls::pose_scene(s, 1.0);
  const double c120 = -0.5, s120 = 0.8660254037844386;
  check_matrix(s.instances[0].object_to_world, rot_z(c120, s120, {2, 1, 0}), "node 1 at 1 s");
  check_matrix(s.instances[1].object_to_world, columns({2, 0, 0}, {0, 3, 0}, {0, 0, 4}, {7, 0, 0}), "node 2 at 1 s");
  check_matrix(s.instances[2].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {3, 1, 0}), "node 3 at 1 s");
  check_vec(s.camera.position, {0, 0, 10}, "camera at 1 s");
  ls::pose_scene(s, 10.0);
  check_matrix(s.instances[0].object_to_world, rot_z(c120, s120, {4, 1, 0}), "node 1 after the end");
  check_matrix(s.instances[1].object_to_world, columns({2, 0, 0}, {0, 3, 0}, {0, 0, 4}, {9, 0, 0}), "node 2 after the end");
  check_matrix(s.instances[2].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {5, 1, 0}), "node 3 after the end");
  ls::pose_scene(s, 0.0);  // the first keys: identity rotation, scale 1, rig at the origin
  check_matrix(s.instances[0].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 1, 0}), "node 1 at 0 s");
  check_matrix(s.instances[2].object_to_world, columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}), "node 3 at 0 s");
}

TEST_CASE("glTF animation: sample_channel follows the specification's formulas", "[animation]") {
  ls::AnimationChannel c;
  c.path = ls::AnimationPath::Rotation;
  c.times = {1.0f, 3.0f};
  const float h = 0.70710678f;
  c.values = {{0, 0, 0, 1}, {0, h, 0, h}};  // identity -> 90 degrees about +y
  const glm::dvec4 q = ls::sample_channel(c, 2.0);  // halfway: 45 degrees, (0, sin 22.5, 0, cos 22.5)
  CHECK(std::fabs(q.y - 0.38268343236508984) < 1e-7);
  CHECK(std::fabs(q.w - 0.9238795325112867) < 1e-7);
  CHECK(ls::sample_channel(c, 0.0) == glm::dvec4(0, 0, 0, 1));  // before the first key
  c.interpolation = ls::Interpolation::Step;
  CHECK(ls::sample_channel(c, 2.999) == glm::dvec4(0, 0, 0, 1));
  c.path = ls::AnimationPath::Scale;
  c.interpolation = ls::Interpolation::Linear;
  c.values = {{1, 2, 3, 0}, {3, 2, 1, 0}};
  CHECK(ls::sample_channel(c, 1.5) == glm::dvec4(1.5, 2, 2.5, 0));  // a quarter of the way, exact in binary
}

TEST_CASE("glTF animation: normalized integer rotations decode as the specification says", "[animation]") {
  const std::string json = file_with(R"([{"mesh":0}])", [](Gltf& g) {
    const int in = g.scalars({0.0f, 1.0f});
    const std::vector<int16_t> q = {0, 0, 0, 32767, 0, 0, 32767, 32767};  // identity, then 90 degrees about +z
    const int bv = g.view(q.data(), q.size() * 2);
    const int out = g.accessor(R"({"bufferView":)" + std::to_string(bv) + R"(,"componentType":5122,"normalized":true,"count":2,"type":"VEC4"})");
    return "[{\"channels\":[" + channel_json(0, 0, "rotation") + "],\"samplers\":[" + sampler_json(in, out, "STEP") + "]}]";
  });
  ls::Scene s = load(json);
  ls::pose_scene(s, 1.0);
  check_matrix(s.instances[0].object_to_world, rot_z(0.0, 1.0, {0, 0, 0}), "90 degrees about z");
}

TEST_CASE("glTF animation: a scene without animations keeps its transforms bit for bit when posed", "[animation]") {
  const std::string json = one_triangle_gltf(R"("nodes":[{"mesh":0,"rotation":[0.1,0.2,0.3,0.9],"translation":[1.5,2,3]}])");
  ls::Scene s = load(json);
  const glm::mat4 before = s.instances[0].object_to_world;
  ls::pose_scene(s, 3.0);
  CHECK(std::memcmp(&before, &s.instances[0].object_to_world, sizeof(before)) == 0);
  CHECK(s.rig.animations.empty());
}

TEST_CASE("glTF animation: several animations, the one asked for is posed, and a missing one is refused", "[animation]") {
  const std::string json = file_with(R"([{"mesh":0}])", [](Gltf& g) {
    const int in = g.scalars({0.0f, 1.0f});
    const int a = g.vec3({{0, 0, 0}, {2, 0, 0}}), b = g.vec3({{0, 0, 0}, {0, 4, 0}});
    return "[{\"name\":\"x\",\"channels\":[" + channel_json(0, 0, "translation") + "],\"samplers\":[" + sampler_json(in, a, "LINEAR") +
           "]},{\"name\":\"y\",\"channels\":[" + channel_json(0, 0, "translation") + "],\"samplers\":[" + sampler_json(in, b, "LINEAR") + "]}]";
  });
  ls::Scene s = load(json);
  REQUIRE(s.rig.animations.size() == 2);
  CHECK(s.rig.animations[1].name == "y");
  ls::pose_scene(s, 0.5, 1);
  check_vec(glm::vec3(s.instances[0].object_to_world[3]), {0, 2, 0}, "animation 1 at 0.5 s");
  ls::pose_scene(s, 0.5, 0);
  check_vec(glm::vec3(s.instances[0].object_to_world[3]), {1, 0, 0}, "animation 0 at 0.5 s");
  CHECK_THROWS_AS(ls::pose_scene(s, 0.5, 2), ls::InputError);
}

TEST_CASE("glTF animation: morph-target weight channels load for still renders and are refused when posed", "[animation]") {
  const std::string json = file_with(R"([{"mesh":0}])", [](Gltf& g) {
    const int in = g.scalars({0.0f, 1.0f});
    const int w = g.scalars({0.0f, 0.5f, 1.0f, 0.25f});  // two targets, two keys
    return "[{\"channels\":[" + channel_json(0, 0, "weights") + "],\"samplers\":[" + sampler_json(in, w, "LINEAR") + "]}]";
  });
  ls::Scene s = load(json);
  REQUIRE(s.rig.animations.size() == 1);
  CHECK(s.rig.animations[0].weight_channels == 1);
  CHECK(s.rig.animations[0].channels.empty());
  try {
    ls::pose_scene(s, 0.5);
    FAIL("posed");
  } catch (const ls::InputError& e) {
    CHECK(std::string(e.what()).find("morph-target weights") != std::string::npos);
  }
}

TEST_CASE("glTF animation: a pose with a singular transform is refused like a static one", "[animation]") {
  ls::Scene s = load(file_with(R"([{"mesh":0}])", one_channel({0.0f, 1.0f}, v4({{1, 1, 1}, {0, 1, 1}}), "STEP", "scale")));
  ls::pose_scene(s, 0.5);  // scale 1
  try {
    ls::pose_scene(s, 1.0);
    FAIL("posed");
  } catch (const ls::InputError& e) {
    const std::string m = e.what();
    INFO(m);
    CHECK(m.find("singular") != std::string::npos);
    CHECK(m.find("t = 1 s") != std::string::npos);
    CHECK(m.find('\n') == std::string::npos);
  }
}

TEST_CASE("glTF animation: hostile animation data is an input error with a one-line reason", "[animation]") {
  const float nan = std::nanf(""), inf = INFINITY;
  const std::vector<glm::vec4> two = v4({{0, 0, 0}, {1, 0, 0}});
  struct Case {
    const char* what;
    std::string json;
    const char* reason;
  };
  const std::string node = R"([{"mesh":0}])";
  const auto raw = [&](const std::string& channels, const std::string& samplers, const std::string& nodes = R"([{"mesh":0}])") {
    return file_with(nodes, [&](Gltf& g) {
      g.scalars({0.0f, 1.0f});                    // accessor 2: key times
      g.vec3({{0, 0, 0}, {1, 0, 0}});              // accessor 3: two translations
      g.indices(std::vector<uint16_t>{0, 1});      // accessor 4: unsigned short scalars
      g.accessor(R"({"bufferView":0,"componentType":5123,"count":2,"type":"VEC3"})");  // 5: unsigned short VEC3
      g.vec4({{0, 0, 0, 1}, {0, 0, 1, 0}});        // accessor 6: float rotations
      g.accessor(R"({"bufferView":0,"componentType":5122,"count":2,"type":"VEC4"})");  // 7: shorts, not normalized
      g.accessor(R"({"componentType":5126,"count":0,"type":"SCALAR"})");              // 8: no keys
      return "[{\"channels\":[" + channels + "],\"samplers\":[" + samplers + "]}]";
    });
  };
  const std::string ch = channel_json(0, 0, "translation");
  const std::vector<Case> cases = {
      {"times not increasing", file_with(node, one_channel({0.0f, 1.0f, 1.0f}, v4({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}))), "not strictly increasing"},
      {"times decreasing", file_with(node, one_channel({1.0f, 0.5f}, two)), "not strictly increasing"},
      {"negative first time", file_with(node, one_channel({-1.0f, 0.5f}, two)), "negative"},
      {"NaN time", file_with(node, one_channel({0.0f, nan}, two)), "NaN or infinite"},
      {"infinite time", file_with(node, one_channel({0.0f, inf}, two)), "NaN or infinite"},
      {"NaN value", file_with(node, one_channel({0.0f, 1.0f}, v4({{0, 0, 0}, {nan, 0, 0}}))), "NaN or infinite"},
      {"infinite value", file_with(node, one_channel({0.0f, 1.0f}, v4({{0, 0, 0}, {0, -inf, 0}}), "LINEAR", "scale")), "NaN or infinite"},
      {"values do not match keys", file_with(node, one_channel({0.0f, 1.0f}, v4({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}))), "expected 2"},
      {"cubic spline without tangents", file_with(node, one_channel({0.0f, 1.0f}, two, "CUBICSPLINE")), "expected 6"},
      {"zero-length quaternion", file_with(node, one_channel({0.0f, 1.0f}, {{0, 0, 0, 1}, {0, 0, 0, 0}}, "LINEAR", "rotation")), "zero length"},
      {"node out of range", file_with(node, one_channel({0.0f, 1.0f}, two, "LINEAR", "translation", 7)), "node 7 does not exist"},
      {"unknown interpolation", file_with(node, one_channel({0.0f, 1.0f}, two, "SMOOTH")), "unknown interpolation"},
      {"unknown path", raw(channel_json(0, 0, "colour"), sampler_json(2, 3, "LINEAR")), "unknown target path"},
      {"sampler out of range", raw(channel_json(3, 0, "translation"), sampler_json(2, 3, "LINEAR")), "sampler 3 does not exist"},
      {"input accessor out of range", raw(ch, sampler_json(42, 3, "LINEAR")), "accessor 42 does not exist"},
      {"output accessor out of range", raw(ch, sampler_json(2, 42, "LINEAR")), "accessor 42 does not exist"},
      {"integer key times", raw(ch, sampler_json(4, 3, "LINEAR")), "unsupported component type"},
      {"integer translations", raw(ch, sampler_json(2, 5, "LINEAR")), "unsupported component type"},
      {"integer rotations not normalized", raw(channel_json(0, 0, "rotation"), sampler_json(2, 7, "LINEAR")), "not normalized"},
      {"key times of the wrong type", raw(ch, sampler_json(3, 3, "LINEAR")), "wrong type"},
      {"no keyframes", raw(ch, sampler_json(8, 3, "LINEAR")), "no keyframes"},
      {"two channels on one property", raw(ch + "," + ch, sampler_json(2, 3, "LINEAR")), "already has a translation channel"},
      {"an animated node with a matrix", raw(ch, sampler_json(2, 3, "LINEAR"), R"([{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}])"),
       "has a matrix"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    try {
      load(c.json);
      FAIL("loaded");
    } catch (const ls::InputError& e) {
      const std::string m = e.what();
      INFO(m);
      CHECK(m.find(c.reason) != std::string::npos);
      CHECK(m.find("anim.gltf: animation 0") == 0);
      CHECK(m.find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("builtin:carousel: 24 animated instances of two meshes inside the room, looping every 4 s", "[animation][scenes]") {
  ls::Scene s = ls::load_scene("builtin:carousel");
  CHECK(s.meshes.size() == 11);
  CHECK(s.instances.size() == 33);
  CHECK(ls::triangle_count(s) == 238778);
  REQUIRE(s.rig.animations.size() == 1);
  const ls::Animation& a = s.rig.animations[0];
  CHECK(a.weight_channels == 0);
  CHECK(a.duration() == 4.0);
  bool linear = false, step = false, cubic = false, translation = false, rotation = false, scale = false;
  for (const ls::AnimationChannel& c : a.channels) {
    linear |= c.interpolation == ls::Interpolation::Linear;
    step |= c.interpolation == ls::Interpolation::Step;
    cubic |= c.interpolation == ls::Interpolation::CubicSpline;
    translation |= c.path == ls::AnimationPath::Translation;
    rotation |= c.path == ls::AnimationPath::Rotation;
    scale |= c.path == ls::AnimationPath::Scale;
  }
  CHECK((linear && step && cubic && translation && rotation && scale));
  const ls::Scene start = s;
  std::vector<bool> moved(33, false);
  for (int f = 1; f <= 96; f += 5) {
    ls::pose_scene(s, f / 24.0);
    const ls::Bounds b = ls::world_bounds(s);
    INFO("frame " << f);
    CHECK(b.lo.x >= -7.5f);
    CHECK(b.lo.y >= 0.0f);
    CHECK(b.lo.z >= -7.5f);
    CHECK(b.hi.x <= 7.5f);
    CHECK(b.hi.y <= 6.0f);
    CHECK(b.hi.z <= 7.5f);
    for (size_t i = 0; i < 9; ++i)  // room, light, pedestal and sphere stay
      CHECK(std::memcmp(&s.instances[i].object_to_world, &start.instances[i].object_to_world, sizeof(glm::mat4)) == 0);
    for (size_t i = 9; i < 33; ++i)
      if (std::memcmp(&s.instances[i].object_to_world, &start.instances[i].object_to_world, sizeof(glm::mat4)) != 0) moved[i] = true;
  }
  CHECK(std::count(moved.begin(), moved.end(), true) == 24);
  ls::pose_scene(s, 4.0);  // the loop closes
  for (size_t i = 0; i < 33; ++i) check_matrix(s.instances[i].object_to_world, glm::dmat4(start.instances[i].object_to_world), "t = 4 s vs 0 s");
}
