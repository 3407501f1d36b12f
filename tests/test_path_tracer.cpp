// The path tracer against analytic answers and against itself under other structures.
#include "common/render/render_types.h"
#include "cpu/build/build_structures.h"
#include "cpu/render/path_tracer.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace ls;
using test_support::closed_sphere;

namespace {

// A closed cube of 12 triangles, normals inward, every face with material 0.
Mesh closed_cube(float half) {
  Mesh m;
  m.name = "cube";
  for (int i = 0; i < 8; ++i)
    m.positions.push_back(glm::vec3((i & 1) ? half : -half, (i & 2) ? half : -half, (i & 4) ? half : -half));
  const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& q : quads) {
    m.triangles.push_back(glm::uvec3(q[0], q[1], q[2]));
    m.triangles.push_back(glm::uvec3(q[0], q[2], q[3]));
  }
  m.materials.assign(m.triangles.size(), 0);
  m.normals.assign(m.positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  return m;
}

// Inside a closed room where every surface emits Le and reflects with albedo rho, the radiance of
// light paths with at most B + 2 segments is Le * (1 + rho + ... + rho^(B+1)) everywhere.
Scene furnace(float rho, float le) {
  Scene s;
  s.name = "furnace";
  Material mat;
  mat.albedo = glm::vec3(rho);
  mat.emission = glm::vec3(le);
  s.materials.push_back(mat);
  s.meshes.push_back(closed_sphere(1.0f, 24, 48));
  s.meshes.push_back(closed_cube(0.25f));  // a convex object inside, so paths see more than one surface
  s.instances.push_back(Instance{0, glm::mat4(1.0f), "room"});
  Instance obj{1, glm::mat4(1.0f), "box"};
  obj.object_to_world[3] = glm::vec4(0.3f, -0.5f, -0.2f, 1.0f);
  s.instances.push_back(obj);
  s.camera.position = glm::vec3(0.0f, 0.0f, 0.9f);
  s.camera.target = glm::vec3(0.0f);
  s.camera.yfov = 1.2f;
  validate_scene(s);
  return s;
}

glm::dvec3 mean(const std::vector<glm::vec3>& img) {
  glm::dvec3 m(0.0);
  for (const glm::vec3& p : img) m += glm::dvec3(p);
  return m / double(img.size());
}

RenderResult render_with(const Scene& scene, const std::string& schedule, int bounces, int spp, uint32_t size = 32) {
  RenderOptions o;
  o.schedule = parse_schedule(schedule);
  o.bounces = bounces;
  o.spp = spp;
  o.width = o.height = size;
  auto built = build_schedule_structures(scene, o.schedule);
  return render(scene, built, o);
}

}  // namespace

TEST_CASE("white furnace: radiance equals the geometric series of the albedo", "[path_tracer]") {
  const float rho = 0.5f, le = 1.0f;
  const Scene scene = furnace(rho, le);
  for (int bounces : {0, 1, 3}) {
    const RenderResult r = render_with(scene, "bvh", bounces, 32, 48);
    double expected = 0.0;
    for (int j = 0; j <= bounces + 1; ++j) expected += le * std::pow(rho, j);
    const glm::dvec3 m = mean(r.total);
    INFO("bounces " << bounces << ": mean " << m.x << " expected " << expected);
    CHECK(m.x == Approx(expected).epsilon(0.01));
    CHECK(m.y == Approx(m.x).epsilon(1e-6));
    // With no indirect bounce, bounce 0 holds everything: the emitter seen directly plus the light
    // sample at the primary hit, which then carries its full weight.
    if (bounces == 0) CHECK(mean(r.bounce_images[0]).x == Approx(le * (1 + rho)).epsilon(0.01));
    CHECK(r.dropped_samples == 0);
  }
}

TEST_CASE("renders are deterministic and structure-independent for exact structures", "[path_tracer]") {
  const Scene scene = furnace(0.6f, 0.5f);
  const RenderResult a = render_with(scene, "bvh", 2, 2);
  const RenderResult b = render_with(scene, "bvh", 2, 2);
  REQUIRE(a.total == b.total);
  const RenderResult c = render_with(scene, "2l-bvh", 2, 2);
  // Same ids from both exact structures (ties aside) give the same paths: nearly the same image.
  double diff = 0.0;
  for (size_t i = 0; i < a.total.size(); ++i) diff = std::max(diff, double(glm::length(a.total[i] - c.total[i])));
  CHECK(diff < 1e-3);
}

TEST_CASE("a schedule that changes at bounce k leaves bounces < k bit-identical", "[path_tracer]") {
  const Scene scene = furnace(0.7f, 0.3f);
  const RenderResult exact = render_with(scene, "bvh", 3, 2);
  const RenderResult mixed = render_with(scene, "bvh,bvh,2l-bvh", 3, 2);
  REQUIRE(exact.bounce_images[0] == mixed.bounce_images[0]);
  REQUIRE(exact.bounce_images[1] == mixed.bounce_images[1]);
  REQUIRE(mixed.bounces[2].structure == "2l-bvh");
  REQUIRE(mixed.bounces[3].structure == "2l-bvh");
  REQUIRE(mixed.bounces[1].structure == "bvh");
}

TEST_CASE("ray counts: every camera ray is counted at bounce 0, indirect rays apart", "[path_tracer]") {
  const Scene scene = furnace(0.5f, 1.0f);
  const RenderResult r = render_with(scene, "bvh", 2, 3, 16);
  CHECK(r.bounces[0].extension_rays == 16u * 16u * 3u);
  // In a closed room every path survives every bounce.
  CHECK(r.bounces[1].extension_rays == 16u * 16u * 3u);
  CHECK(r.bounces[2].extension_rays == 16u * 16u * 3u);
  CHECK(r.indirect_rays() == r.bounces[1].extension_rays + r.bounces[1].shadow_rays + r.bounces[2].extension_rays +
                                 r.bounces[2].shadow_rays);
  CHECK(r.indirect_mrays_per_s() > 0.0);
}
