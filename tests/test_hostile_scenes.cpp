// Hostile scenes not covered by test_scenes' bad-input cases: wrong component types, every
// non-triangle mode, float overflow in vertices, transforms and emission, denormal and zero-area
// geometry, 2^31 triangles, extreme cameras, zero- and huge-power lights.  Each is refused with an
// InputError naming the file, or loads and renders finite pixels.  Through load_gltf_bytes: no files.
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/build/structure_budget.h"
#include "cpu/render/path_tracer.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"
#include "tests/gltf_writer.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <limits>

using namespace ls;
using namespace ls_test;
using Catch::Matchers::Contains;

namespace {

Scene gltf(const std::string& json) { return load_gltf_bytes(json, "hostile.gltf", false); }

void refused(const std::string& json, const std::string& reason, const char* why) {
  INFO(why);
  CHECK_THROWS_AS(gltf(json), InputError);
  CHECK_THROWS_WITH(gltf(json), Contains("hostile.gltf") && Contains(reason));
}

// One triangle's positions as the given accessor JSON reads them, and a primitive using it.
std::string with_accessor(const std::string& accessor, const std::string& primitive_extra = "",
                          const std::string& materials = "") {
  return R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,)" +
         base64(std::string(reinterpret_cast<const char*>(kTriangle.data()), 36)) +
         R"("}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[)" + accessor +
         R"(],"meshes":[{"primitives":[{"attributes":{"POSITION":0})" + primitive_extra + R"(}]}],)" + materials +
         R"("nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})";
}
const std::string kPositions = R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"})";

// A glTF of the given triangles (one primitive, material 0 = `material`) under node 0; `rest`
// continues the nodes array after node 0 and must close it.
std::string triangles_gltf(const std::vector<glm::vec3>& positions, const std::string& material,
                           const std::string& node_extra = "", const std::string& rest = "]") {
  Gltf g;
  const int pos = g.vec3(positions);
  return g.json(R"("materials":[)" + material + R"(],"meshes":[{"primitives":[{"attributes":{"POSITION":)" +
                std::to_string(pos) + R"(},"material":0}]}],"nodes":[{"mesh":0)" + node_extra + "}" + rest);
}

RenderResult render_small(const Scene& scene, int bounces = 1) {
  RenderOptions o;
  o.schedule = parse_schedule("bvh");
  o.bounces = bounces;
  o.spp = 2;
  o.width = o.height = 12;
  const auto built = build_schedule_structures(scene, o.schedule);
  return render(scene, built, o);
}

bool finite(const glm::vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

bool all_finite(const RenderResult& r) {
  for (const auto& img : r.bounce_images)
    for (const glm::vec3& p : img)
      if (!finite(p)) return false;
  for (const glm::vec3& p : r.total)
    if (!finite(p)) return false;
  return true;
}

// A lit quad facing +z (two triangles) plus the given extra triangles.
std::vector<glm::vec3> quad_and(const std::vector<glm::vec3>& extra) {
  std::vector<glm::vec3> p = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  p.insert(p.end(), extra.begin(), extra.end());
  return p;
}

}  // namespace

TEST_CASE("hostile glTF: wrong component types are refused", "[hostile]") {
  REQUIRE_NOTHROW(gltf(with_accessor(kPositions)));
  // POSITION must be float VEC3; indices unsigned 8/16/32-bit scalars.
  refused(with_accessor(R"({"bufferView":0,"componentType":5123,"count":3,"type":"VEC3"})"), "component type",
          "POSITION as unsigned short");
  refused(with_accessor(R"({"bufferView":0,"componentType":5120,"count":3,"type":"VEC3"})"), "component type",
          "POSITION as signed byte");
  refused(with_accessor(kPositions + R"(,{"bufferView":0,"componentType":5126,"count":3,"type":"SCALAR"})", R"(,"indices":1)"),
          "component type", "float indices");
  refused(with_accessor(kPositions + R"(,{"bufferView":0,"componentType":5122,"count":3,"type":"SCALAR"})", R"(,"indices":1)"),
          "component type", "signed short indices");
  refused(with_accessor(kPositions + R"(,{"bufferView":0,"componentType":5121,"count":3,"type":"VEC3"})",
                        R"(,"indices":1)"),
          "wrong type", "indices of type VEC3");
  std::string normal_vec2 = with_accessor(kPositions + R"(,{"bufferView":0,"componentType":5126,"count":3,"type":"VEC2"})");
  normal_vec2.replace(normal_vec2.find(R"({"POSITION":0})"), 14, R"({"POSITION":0,"NORMAL":1})");
  refused(normal_vec2, "NORMAL accessor 1 has the wrong type", "NORMAL of type VEC2");
  refused(with_accessor(R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","sparse":{"count":1,)"
                        R"("indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":0}}})"),
          "sparse", "sparse accessor");
}

TEST_CASE("hostile glTF: every non-triangle and unknown primitive mode is refused", "[hostile]") {
  for (int mode : {0, 1, 2, 3}) refused(with_accessor(kPositions, R"(,"mode":)" + std::to_string(mode)), "non-triangle", "points/lines");
  for (int mode : {7, 100, -5}) {
    INFO("mode " << mode);
    CHECK_THROWS_AS(gltf(with_accessor(kPositions, R"(,"mode":)" + std::to_string(mode))), InputError);
  }
  for (int mode : {4, 5, 6}) CHECK_NOTHROW(gltf(with_accessor(kPositions, R"(,"mode":)" + std::to_string(mode))));
}

TEST_CASE("hostile glTF: values beyond float range in vertices, transforms and emission are refused", "[hostile]") {
  const std::string grey = R"({"pbrMetallicRoughness":{"baseColorFactor":[0.5,0.5,0.5,1]}})";
  refused(triangles_gltf({{0, 0, 0}, {1, 0, 0}, {0, std::numeric_limits<float>::infinity(), 0}}, grey), "infinite",
          "an infinite vertex");
  refused(triangles_gltf(kTriangle, grey, R"(,"translation":[1e39,0,0])"), "infinite", "translation past float");
  refused(triangles_gltf(kTriangle, grey, R"(,"scale":[1e30,1e30,1e30],"translation":[0,0,0])",
                         R"(,{"children":[0],"scale":[1e30,1,1]}],"scenes":[{"nodes":[1]}])"),
          "", "parent x child scale past float");
  refused(triangles_gltf(kTriangle, R"({"emissiveFactor":[1e39,1,1]})"), "infinite", "emission past float");
  refused(triangles_gltf(kTriangle, R"({"emissiveFactor":[10,10,10],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":1e38}}})"),
          "infinite", "emissive strength overflowing float");
  refused(triangles_gltf(kTriangle, R"({"emissiveFactor":[-1,0,0]})"), "negative", "negative emission");
  refused(triangles_gltf(kTriangle, R"({"pbrMetallicRoughness":{"baseColorFactor":[1e39,0.5,0.5,1]}})"), "infinite",
          "albedo past float");
}

TEST_CASE("hostile glTF: denormal and zero-area triangles load and render finite pixels", "[hostile]") {
  const std::string lit = R"({"pbrMetallicRoughness":{"baseColorFactor":[0.5,0.5,0.5,1]},"emissiveFactor":[1,1,1]})";
  // Denormal coordinates: valid floats; the scene is tiny but traceable.
  const float d = 1e-40f;
  REQUIRE(std::fpclassify(d) == FP_SUBNORMAL);
  const Scene tiny = gltf(triangles_gltf({{0, 0, 0}, {d, 0, 0}, {0, d, 0}}, lit));
  CHECK(all_finite(render_small(tiny)));
  // Zero-area triangles (a repeated vertex, collinear vertices) beside a lit quad: never hit, and an
  // emissive one is no light (its area is 0), so nothing divides by it.
  const Scene degenerate = gltf(triangles_gltf(quad_and({{0, 0, 1}, {0, 0, 1}, {1, 0, 1}, {0, 0, 2}, {1, 1, 2}, {2, 2, 2}}), lit));
  const Accel accel = build_accel(degenerate, parse_structure("bvh"));
  lsk::Ray ray{};
  ray.origin = glm::vec3(0.25f, 0.25f, 5.0f);  // straight down through the collinear triangle's line
  ray.dir = glm::vec3(0.0f, 0.0f, -1.0f);
  ray.tmax = lsk::ls_infinity();
  lsk::Hit hit{};
  trace_rays(accel, LsLookup{}, &ray, &hit, 1, false);
  CHECK(hit.triangle < 2u);  // the quad, not a degenerate triangle
  const RenderResult r = render_small(degenerate);
  CHECK(all_finite(r));
  CHECK(r.dropped_samples == 0);
  // Only zero-area triangles: they load (nothing to refuse) and are never hit.
  const Scene only_degenerate = load_mesh_bytes("v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\nf 1 1 2\n", ".obj", "flat.obj");
  const RenderResult rd = render_small(only_degenerate);
  CHECK(all_finite(rd));
  CHECK(rd.bounces[0].extension_rays == 12u * 12u * 2u);
}

TEST_CASE("hostile scenes: 2^31 world triangles are refused, a 2^30-triangle flat BVH by the budget", "[hostile]") {
  // One mesh of 65,536 copies of one triangle, instanced many times: cheap to describe, huge to build.
  Scene scene;
  scene.name = "many";
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.normals.assign(3, glm::vec3(0, 0, 1));
  mesh.triangles.assign(size_t(1) << 16, glm::uvec3(0, 1, 2));
  mesh.materials.assign(mesh.triangles.size(), 0);
  scene.meshes.push_back(mesh);
  scene.materials.push_back(Material{});
  scene.camera.position = glm::vec3(0, 0, 5);
  for (int i = 0; i < (1 << 15); ++i) {
    Instance inst;
    inst.object_to_world[3] = glm::vec4(0.0f, 0.0f, -float(i), 1.0f);
    scene.instances.push_back(inst);
  }
  CHECK_THROWS_WITH(validate_scene(scene), Contains("2^31"));
  scene.instances.resize(size_t(1) << 14);  // 2^30 world triangles: valid, but no flat BVH fits
  REQUIRE_NOTHROW(validate_scene(scene));
  const auto start = std::chrono::steady_clock::now();
  CHECK_THROWS_WITH(check_structure_budget(scene, parse_structure("bvh"), AccelOptions{}), Contains("BVH and triangles"));
  CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < 2.0);
  // The two-level structure holds the mesh once: it fits.
  CHECK_NOTHROW(check_structure_budget(scene, parse_structure("2l-bvh"), AccelOptions{}));
}

TEST_CASE("hostile glTF: extreme and missing cameras", "[hostile]") {
  const std::string lit = R"({"emissiveFactor":[1,1,1]})";
  const auto with_camera = [&](const std::string& camera, const std::string& camera_node) {
    return triangles_gltf(quad_and({}), lit, "",
                          R"(,)" + camera_node + R"(],"cameras":[)" + camera + R"(],"scenes":[{"nodes":[0,1]}])");
  };
  const std::string persp = R"({"type":"perspective","perspective":{"yfov":YFOV,"znear":0.1}})";
  const auto yfov = [&](const std::string& v) { return std::string(persp).replace(persp.find("YFOV"), 4, v); };
  // A pinhole of 1e-6 radians and one 1e30 away: finite rays, finite pixels.
  CHECK(all_finite(render_small(gltf(with_camera(yfov("1e-6"), R"({"camera":0,"translation":[0,0,5]})")))));
  CHECK(all_finite(render_small(gltf(with_camera(yfov("0.8"), R"({"camera":0,"translation":[0,0,1e30]})")))));
  refused(with_camera(yfov("3.2"), R"({"camera":0,"translation":[0,0,5]})"), "yfov", "field of view past pi");
  refused(with_camera(yfov("0"), R"({"camera":0,"translation":[0,0,5]})"), "", "zero field of view");
  refused(with_camera(yfov("0.8"), R"({"camera":0,"scale":[0,0,0]})"), "degenerate transform", "camera scaled to a point");
  // No perspective camera (an orthographic one only): the framing camera.
  const Scene ortho = gltf(with_camera(R"({"type":"orthographic","orthographic":{"xmag":1,"ymag":1,"zfar":10,"znear":0.1}})",
                                       R"({"camera":0,"translation":[0,0,5]})"));
  CHECK(ortho.camera.position == framing_camera(ortho).position);
}

TEST_CASE("hostile glTF: zero-power lights render black, huge ones finite with the overflow counted", "[hostile]") {
  // A closed-ish box would be nicer; a quad facing the framing camera suffices.
  const RenderResult dark = render_small(gltf(triangles_gltf(quad_and({}), R"({"emissiveFactor":[0,0,0]})")));
  CHECK(all_finite(dark));
  for (const glm::vec3& p : dark.total) CHECK(p == glm::vec3(0.0f));
  // 3e38 is a finite emission; sums of such contributions pass the float range and are dropped
  // (counted), never written as Inf.
  const Scene hot = gltf(triangles_gltf(quad_and({}), R"({"pbrMetallicRoughness":{"baseColorFactor":[1,1,1,1]},"emissiveFactor":[3e38,3e38,3e38]})"));
  const RenderResult r = render_small(hot, 2);
  CHECK(all_finite(r));
  CHECK(r.dropped_samples > 0);
}
