// The per-path structure choice (render --throughput-switch T:X) against renders that must equal it:
// a T above every throughput is X from bounce 0, a tiny T is the schedule, switching to the
// schedule's own structure changes nothing, and bounce 0 (throughput 1) is never switched by T <= 1.
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/render/path_tracer.h"
#include "scenes/load_scene.h"

#include <catch2/catch.hpp>

#include <cstring>

using namespace ls;

namespace {

RenderResult render_policy(const Scene& scene, const std::string& schedule, const std::string& policy) {
  RenderOptions o;
  o.schedule = parse_schedule(schedule);
  o.width = 40;
  o.height = 30;
  o.spp = 2;
  o.bounces = 3;
  o.seed = 4;
  if (!policy.empty()) o.throughput_switch = parse_throughput_switch(policy);
  AccelOptions a;
  a.ls.min_triangles = 0;  // Line Space nodes on cornell's small objects too: approximations that show
  const auto built = build_schedule_structures(scene, o.schedule, a, o.throughput_switch);
  return render(scene, built, o);
}

bool same_bits(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0;
}

void require_same_images(const RenderResult& a, const RenderResult& b) {
  REQUIRE(a.bounce_images.size() == b.bounce_images.size());
  for (size_t k = 0; k < a.bounce_images.size(); ++k) {
    INFO("bounce " << k);
    REQUIRE(same_bits(a.bounce_images[k], b.bounce_images[k]));
  }
  REQUIRE(same_bits(a.total, b.total));
}

uint64_t switched(const BounceStats& b) { return b.switched_extension_rays + b.switched_shadow_rays; }
uint64_t rays(const BounceStats& b) { return b.extension_rays + b.shadow_rays; }

}  // namespace

TEST_CASE("throughput switch: T above every throughput equals the switch's structure from bounce 0", "[throughput_switch]") {
  const Scene scene = load_scene("builtin:cornell");
  const RenderResult policy = render_policy(scene, "bvh", "1.5:f-ls:3:6");
  const RenderResult all_ls = render_policy(scene, "f-ls:3:6", "");
  require_same_images(policy, all_ls);
  for (size_t k = 0; k < policy.bounces.size(); ++k) {
    INFO("bounce " << k);
    REQUIRE(rays(policy.bounces[k]) == rays(all_ls.bounces[k]));
    REQUIRE(switched(policy.bounces[k]) == rays(policy.bounces[k]));
    REQUIRE(std::memcmp(&policy.bounces[k].switched_ls, &all_ls.bounces[k].ls, sizeof(lsk::LsCounters)) == 0);
    REQUIRE(std::memcmp(&policy.bounces[k].ls, &all_ls.bounces[k].ls, sizeof(lsk::LsCounters)) == 0);
  }
  REQUIRE(policy.bounces[1].ls.accepted > 0);  // the Line Space approximated, so equality means something
}

TEST_CASE("throughput switch: a tiny T equals the schedule bit for bit and switches nothing", "[throughput_switch]") {
  const Scene scene = load_scene("builtin:cornell");
  const RenderResult policy = render_policy(scene, "bvh,f-ls:3:6", "1e-30:2l-ls:2:6");
  const RenderResult schedule = render_policy(scene, "bvh,f-ls:3:6", "");
  require_same_images(policy, schedule);
  for (const BounceStats& b : policy.bounces) REQUIRE(switched(b) == 0);
}

TEST_CASE("throughput switch: switching to the schedule's own structure changes no image", "[throughput_switch]") {
  // The switched paths are gathered and traced as a batch of their own: with the same structure, a
  // mistake in that bookkeeping (lost rays, hits given to the wrong path) would show here.
  const Scene scene = load_scene("builtin:cornell");
  const RenderResult policy = render_policy(scene, "bvh,f-ls:3:6", "0.4:f-ls:3:6");
  const RenderResult schedule = render_policy(scene, "bvh,f-ls:3:6", "");
  require_same_images(policy, schedule);
  uint64_t moved = 0, total = 0;
  for (size_t k = 0; k < policy.bounces.size(); ++k) {
    REQUIRE(rays(policy.bounces[k]) == rays(schedule.bounces[k]));
    REQUIRE(std::memcmp(&policy.bounces[k].ls, &schedule.bounces[k].ls, sizeof(lsk::LsCounters)) == 0);
    moved += switched(policy.bounces[k]);
    total += rays(policy.bounces[k]);
  }
  REQUIRE(moved > 0);
  REQUIRE(moved < total);
}

TEST_CASE("throughput switch: T <= 1 keeps bounce 0 exact and switches some later paths", "[throughput_switch]") {
  const Scene scene = load_scene("builtin:cornell");
  const RenderResult exact = render_policy(scene, "bvh", "");
  const RenderResult policy = render_policy(scene, "bvh", "0.3:f-ls:3:6");
  REQUIRE(switched(policy.bounces[0]) == 0);
  REQUIRE(same_bits(policy.bounce_images[0], exact.bounce_images[0]));
  // Bounce 1's extension rays are the reference's (its paths are exact up to there); some switch.
  REQUIRE(policy.bounces[1].extension_rays == exact.bounces[1].extension_rays);
  REQUIRE(policy.bounces[1].switched_extension_rays > 0);
  REQUIRE(policy.bounces[1].switched_extension_rays < policy.bounces[1].extension_rays);
  // With an exact schedule every Line Space lookup is a switched ray's.
  for (const BounceStats& b : policy.bounces) REQUIRE(std::memcmp(&b.ls, &b.switched_ls, sizeof(lsk::LsCounters)) == 0);
  REQUIRE_FALSE(same_bits(policy.total, exact.total));
}

TEST_CASE("throughput switch: T must be a finite number above 0 and the structure a structure", "[throughput_switch]") {
  const ThroughputSwitch s = parse_throughput_switch("0.25:2l-ls:4:6");
  REQUIRE(s.threshold == 0.25f);
  REQUIRE(s.structure.name() == "2l-ls:4:6");
  REQUIRE(s.name() == "0.25:2l-ls:4:6");
  REQUIRE(parse_throughput_switch("0.3:bvh").name() == "0.3:bvh");
  REQUIRE(parse_throughput_switch("1e-30:f-ls(3,6)").structure.name() == "f-ls:3:6");
  for (const char* bad : {"0:bvh", "-1:bvh", "nan:bvh", "inf:bvh", "1e39:bvh", "abc:bvh", "0.5", "0.5:", ":bvh", "0.5:octree",
                          "0.5 :bvh", "", "0x1p-3:bvh"})
    REQUIRE_THROWS_AS(parse_throughput_switch(bad), InputError);
  REQUIRE_FALSE(ThroughputSwitch{}.enabled());
}
