// The Vulkan port against the CPU reference, bit for bit (docs/design.md §5): Line Space candidates of
// every shaft, traced hits (closest and any hit, all four structures), and renders.  These run on
// whatever Vulkan device the machine has (lavapipe in CI); with no device at all they FAIL.
#include "common/model/animation.h"
#include "common/render/render_types.h"
#include "common/render/tile_selection.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/build/top_level_update.h"
#include "cpu/render/path_tracer.h"
#include "cpu/trace/ray_generators.h"
#include "gpu/gpu_line_space.h"
#include "gpu/gpu_renderer.h"
#include "scenes/load_scene.h"
#include "validate/cross_check.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <limits>
#include <memory>

using namespace ls;

namespace {

// One device for the whole test process (instance creation costs tens of ms, more the first time).
const gpu::VulkanContext& device() {
  static const std::unique_ptr<gpu::VulkanContext> context = std::make_unique<gpu::VulkanContext>();
  return *context;
}

AccelOptions paper() {  // every node at depth D gets a Line Space, as in the paper
  AccelOptions o;
  o.ls.min_triangles = 0;
  return o;
}

Scene scaled(const std::string& spec, float scale, glm::vec3 offset) {
  Scene s = load_scene(spec);
  scale_and_offset(s, scale, offset);
  return s;
}

// A planar grid in z = 0 of 2 x cells^2 triangles: every LS box is flat (widened by the builder).
Scene plane_scene(int cells) {
  Scene s;
  s.name = "plane";
  s.materials.push_back(Material{});
  s.meshes.push_back(test_support::square_grid(cells));
  s.instances.push_back(Instance{0, glm::mat4(1.0f), "plane"});
  s.camera = framing_camera(s);
  validate_scene(s);
  return s;
}

void require_candidates_equal(const Scene& scene, const std::string& structure, const AccelOptions& options = paper()) {
  INFO(scene.name << " " << structure);
  const validate::CrossCheckResult r = validate::cross_check_candidates(device(), scene, parse_structure(structure), options);
  if (!r.ok()) validate::print_cross_check(stderr, scene.name + " " + structure + " candidates", r);
  REQUIRE(r.compared > 0);
  REQUIRE(r.mismatches == 0);
}

void require_hits_equal(const Scene& scene, const std::string& structure, const std::vector<lsk::Ray>& rays,
                        const AccelOptions& options = paper(), const LsLookup& lookup = {}) {
  for (bool any_hit : {false, true}) {
    INFO(scene.name << " " << structure << (any_hit ? " any-hit" : " closest"));
    const validate::CrossCheckResult r =
        validate::cross_check_hits(device(), scene, parse_structure(structure), rays, any_hit, options, lookup);
    if (!r.ok()) validate::print_cross_check(stderr, scene.name + " " + structure + " hits", r);
    REQUIRE(r.compared == rays.size());
    REQUIRE(r.mismatches == 0);
  }
}

std::vector<lsk::Ray> diffuse_rays(const Scene& scene, size_t count, uint32_t seed) {
  return generate_rays(scene, build_accel(scene, parse_structure("bvh")), RayKind::Diffuse, count, seed);
}

std::vector<lsk::Ray> random_rays(const Scene& scene, size_t count, uint32_t seed) {
  return generate_rays(scene, build_accel(scene, parse_structure("bvh")), RayKind::Random, count, seed);
}

}  // namespace

TEST_CASE("a Vulkan device is present and named", "[gpu]") {
  // Fails, rather than skips, on a machine without Vulkan: CI has lavapipe.
  REQUIRE_FALSE(device().info().name.empty());
  REQUIRE_FALSE(gpu::VulkanContext::list_devices().empty());
}

TEST_CASE("an unknown --device is bad input", "[gpu]") {
  REQUIRE_THROWS_AS(gpu::VulkanContext("no such device anywhere"), InputError);
  REQUIRE_THROWS_AS(gpu::VulkanContext("99"), InputError);
}

TEST_CASE("GPU candidates equal the CPU's for N in 1 2 6 10 flat and two-level at several depths", "[gpu]") {
  const Scene objects = load_scene("builtin:generated:1200:3:5");
  for (const char* s : {"f-ls:0:1", "f-ls:3:1", "2l-ls:2:1", "f-ls:0:2", "f-ls:4:2", "2l-ls:1:2", "f-ls:2:6", "f-ls:5:6",
                        "2l-ls:0:6", "2l-ls:3:6", "f-ls:1:10", "2l-ls:2:10"})
    require_candidates_equal(objects, s);
}

TEST_CASE("GPU candidates and hits equal the CPU's for per-object D and N and for 2l-ls:auto", "[gpu]") {
  const Scene scene = load_scene("builtin:generated:6000:4:2");
  AccelOptions mixed = paper();
  mixed.ls.objects.assign(scene.meshes.size(), ObjectLs{2, 3});
  mixed.ls.objects[1] = ObjectLs{0, 5};
  mixed.ls.objects[2] = ObjectLs{};
  require_candidates_equal(scene, "2l-ls:0:1", mixed);
  require_hits_equal(scene, "2l-ls:0:1", diffuse_rays(scene, 3000, 4), mixed);
  AccelOptions budget = paper();
  budget.plan.budget = 700000;  // 0.41 MB of it the records and indices every Line Space takes
  budget.plan.rays = 3000;
  budget.plan.lookup.behind = LsBehind::Empty;  // with exact, the pilot's rays from the objects' surfaces gain nothing: no Line Space
  require_candidates_equal(scene, "2l-ls:auto", budget);
}

TEST_CASE("GPU candidates equal the CPU's on cornell with further search rays and both candidate sizes", "[gpu]") {
  const Scene cornell = load_scene("builtin:cornell");
  AccelOptions further = paper();
  further.ls.further_rays = 4;
  require_candidates_equal(cornell, "f-ls:3:6", further);
  AccelOptions four_bytes = paper();
  four_bytes.ls.paper_candidates = true;
  require_candidates_equal(cornell, "2l-ls:2:6", four_bytes);
  require_candidates_equal(cornell, "f-ls:6:2", AccelOptions{});  // default minimum subtree size
}

TEST_CASE("GPU candidates equal the CPU's at the extremes - flat boxes and scales 1e-20 and 1e20 and offset 1e6", "[gpu]") {
  const Scene plane = plane_scene(16);
  for (const char* s : {"f-ls:0:6", "f-ls:3:2", "2l-ls:2:10"}) require_candidates_equal(plane, s);
  for (const float scale : {1e-20f, 1e20f}) {
    const Scene tiny_or_huge = scaled("builtin:generated:800:2:3", scale, glm::vec3(0.0f));
    for (const char* s : {"f-ls:2:6", "2l-ls:1:2"}) require_candidates_equal(tiny_or_huge, s);
  }
  const Scene far = scaled("builtin:generated:800:2:3", 1.0f, glm::vec3(1e6f));
  for (const char* s : {"f-ls:2:6", "2l-ls:1:2"}) require_candidates_equal(far, s);
}

TEST_CASE("GPU hits equal the CPU's bit for bit for all four structures closest and any hit", "[gpu]") {
  const Scene cornell = load_scene("builtin:cornell");
  const std::vector<lsk::Ray> diffuse = diffuse_rays(cornell, 20000, 3);
  for (const char* s : {"bvh", "2l-bvh", "f-ls:3:6", "2l-ls:2:6", "f-ls:5:2"}) require_hits_equal(cornell, s, diffuse);
  const Scene objects = load_scene("builtin:generated:1200:3:5");
  const std::vector<lsk::Ray> random = random_rays(objects, 20000, 4);  // origins inside LS boxes too
  for (const char* s : {"bvh", "2l-bvh", "f-ls:2:10", "2l-ls:1:1"}) require_hits_equal(objects, s, random);
}

TEST_CASE("GPU hits equal the CPU's bit for bit with --ls-behind reverse and empty, at any --ls-leave-reach", "[gpu]") {
  const Scene cornell = load_scene("builtin:cornell");
  const std::vector<lsk::Ray> diffuse = diffuse_rays(cornell, 20000, 3);
  const Scene objects = load_scene("builtin:generated:1200:3:5");
  const std::vector<lsk::Ray> random = random_rays(objects, 20000, 4);  // origins inside LS boxes
  for (LsBehind behind : {LsBehind::Reverse, LsBehind::Empty}) {
    INFO(ls_behind_name(behind));
    LsLookup lookup;
    lookup.behind = behind;
    for (const char* s : {"f-ls:3:6", "2l-ls:2:6", "2l-ls:0:10"}) require_hits_equal(cornell, s, diffuse, paper(), lookup);
    for (const char* s : {"f-ls:2:10", "2l-ls:1:1"}) require_hits_equal(objects, s, random, paper(), lookup);
  }
  for (float reach : {0.0f, std::numeric_limits<float>::infinity()}) {  // the push constant reaches the lookup
    INFO("empty, leave reach " << reach);
    LsLookup lookup;
    lookup.behind = LsBehind::Empty;
    lookup.leave_reach = reach;
    require_hits_equal(cornell, "f-ls:3:6", diffuse, paper(), lookup);
    require_hits_equal(objects, "f-ls:2:10", random, paper(), lookup);
  }
}

TEST_CASE("GPU hits equal the CPU's at the extremes - flat boxes and scales 1e-20 and 1e20 and offset 1e6", "[gpu]") {
  const Scene plane = plane_scene(16);
  const std::vector<lsk::Ray> on_plane = random_rays(plane, 5000, 8);
  for (const char* s : {"bvh", "f-ls:0:6", "2l-ls:2:2"}) require_hits_equal(plane, s, on_plane);
  for (const float scale : {1e-20f, 1e20f}) {
    const Scene tiny_or_huge = scaled("builtin:generated:800:2:3", scale, glm::vec3(0.0f));
    const std::vector<lsk::Ray> rays = random_rays(tiny_or_huge, 5000, 9);
    for (const char* s : {"bvh", "2l-bvh", "f-ls:2:6", "2l-ls:1:2"}) require_hits_equal(tiny_or_huge, s, rays);
  }
  const Scene far = scaled("builtin:generated:800:2:3", 1.0f, glm::vec3(1e6f));
  const std::vector<lsk::Ray> rays = random_rays(far, 5000, 10);
  for (const char* s : {"bvh", "2l-bvh", "f-ls:2:6", "2l-ls:1:2"}) require_hits_equal(far, s, rays);
}

TEST_CASE("the cross-checks report a single changed candidate or hit bit", "[gpu]") {
  const Scene scene = load_scene("builtin:generated:600:2:1");
  const StructureSpec spec = parse_structure("f-ls:2:6");
  const Accel cpu = build_accel(scene, spec, paper());
  Accel changed = cpu;
  REQUIRE(validate::compare_candidate_arrays(cpu, changed).ok());
  changed.ls_candidates[changed.ls_candidates.size() / 2] ^= 1u;
  const validate::CrossCheckResult r = validate::compare_candidate_arrays(cpu, changed);
  REQUIRE(r.mismatches >= 1);
  REQUIRE_FALSE(r.first.empty());

  std::vector<lsk::Hit> hits(3);
  for (lsk::Hit& h : hits) h = lsk::Hit{1.0f, 0u, 5u, 0.25f, 0.5f};
  std::vector<lsk::Hit> other = hits;
  other[1].t = std::nextafter(1.0f, 2.0f);  // one ulp
  const lsk::LsCounters none{};
  REQUIRE(validate::compare_hit_arrays(hits, hits, none, none).ok());
  const validate::CrossCheckResult h = validate::compare_hit_arrays(hits, other, none, none);
  REQUIRE(h.mismatches == 1);
  REQUIRE(h.first[0].where == "ray 1");
}

TEST_CASE("a GPU render gives the CPU render's images bit for bit", "[gpu]") {
  const Scene cornell = load_scene("builtin:cornell");
  RenderOptions options;
  options.schedule = parse_schedule("bvh,f-ls:3:6,2l-ls:2:6");
  options.width = 48;
  options.height = 32;
  options.spp = 2;
  options.bounces = 3;
  options.seed = 7;
  const std::map<std::string, Accel> cpu_built = build_schedule_structures(cornell, options.schedule);
  const std::map<std::string, Accel> gpu_built = gpu::build_schedule_structures_gpu(device(), cornell, options.schedule);
  const RenderResult cpu = render(cornell, cpu_built, options);
  const RenderResult gpu = gpu::render_gpu(device(), cornell, gpu_built, options);
  // The Line Space counters depend on the walk's order: the device's are the reference kernel's.
  AccelOptions reference;
  reference.traversal = Traversal::Reference;
  const RenderResult cpu_reference = render(cornell, build_schedule_structures(cornell, options.schedule, reference), options);
  REQUIRE(gpu.bounce_images.size() == cpu.bounce_images.size());
  for (size_t k = 0; k < cpu.bounce_images.size(); ++k) {
    INFO("bounce " << k);
    REQUIRE(cpu.bounces[k].extension_rays == gpu.bounces[k].extension_rays);
    REQUIRE(cpu.bounces[k].shadow_rays == gpu.bounces[k].shadow_rays);
    REQUIRE(std::memcmp(&cpu_reference.bounces[k].ls, &gpu.bounces[k].ls, sizeof(lsk::LsCounters)) == 0);
    REQUIRE(std::memcmp(cpu_reference.bounce_images[k].data(), gpu.bounce_images[k].data(),
                        cpu.bounce_images[k].size() * sizeof(glm::vec3)) == 0);
    REQUIRE(std::memcmp(cpu.bounce_images[k].data(), gpu.bounce_images[k].data(), cpu.bounce_images[k].size() * sizeof(glm::vec3)) == 0);
  }
  REQUIRE(std::memcmp(cpu.total.data(), gpu.total.data(), cpu.total.size() * sizeof(glm::vec3)) == 0);
  // Not trivially equal: the image holds light.
  float sum = 0.0f;
  for (const glm::vec3& c : gpu.total) sum += c.x + c.y + c.z;
  REQUIRE(sum > 0.0f);
  // The lookup travels with the render: the same structures at another refusal angle and behind
  // mode give other images, and the same ones on both back ends.
  RenderOptions other = options;
  other.lookup.angle_degrees = 10.0f;
  other.lookup.behind = LsBehind::Reverse;
  const RenderResult cpu_other = render(cornell, cpu_built, other);
  const RenderResult gpu_other = gpu::render_gpu(device(), cornell, gpu_built, other);
  REQUIRE(std::memcmp(cpu_other.total.data(), gpu_other.total.data(), cpu_other.total.size() * sizeof(glm::vec3)) == 0);
  CHECK(std::memcmp(cpu_other.total.data(), cpu.total.data(), cpu.total.size() * sizeof(glm::vec3)) != 0);
}

namespace {

// builtin:cornell with a rig: every object a node (its own matrix), the tall box and the sphere on
// animated nodes (a turn about the room's vertical axis, LINEAR, and a slide, CUBICSPLINE).
Scene animated_cornell() {
  Scene s = load_scene("builtin:cornell");
  Animation a;
  a.name = "test";
  for (uint32_t i = 0; i < s.instances.size(); ++i) {
    RigNode node;
    node.instance = int(i);
    node.has_matrix = i != 7 && i != 9;
    node.matrix = glm::dmat4(s.instances[i].object_to_world);
    s.rig.order.push_back(i);
    s.rig.nodes.push_back(node);
  }
  AnimationChannel turn;
  turn.node = 7;
  turn.path = AnimationPath::Rotation;
  turn.times = {0.0f, 1.0f};
  turn.values = {{0, 0, 0, 1}, {0, 0.3826834f, 0, 0.9238795f}};  // 45 degrees about +y
  a.channels.push_back(turn);
  AnimationChannel slide;
  slide.node = 9;
  slide.path = AnimationPath::Translation;
  slide.interpolation = Interpolation::CubicSpline;
  slide.times = {0.0f, 1.0f};
  slide.values = {{0, 0, 0, 0}, {0, 0, 0, 0}, {0.5f, 0, 0, 0}, {0, 0.3f, 0, 0}, {0.6f, 0.1f, -0.2f, 0}, {0, 0, 0, 0}};
  a.channels.push_back(slide);
  s.rig.animations.push_back(a);
  return s;
}

}  // namespace

TEST_CASE("GPU frames with top-level-only updates equal the CPU's bit for bit", "[gpu][animation]") {
  Scene scene = animated_cornell();
  RenderOptions options;
  options.schedule = parse_schedule("bvh,2l-bvh,2l-ls:2:6");
  options.width = 40;
  options.height = 28;
  options.spp = 1;
  options.bounces = 3;
  options.seed = 5;
  std::map<std::string, Accel> cpu, gpu;
  for (const char* name : {"2l-bvh", "2l-ls:2:6"}) {
    cpu.emplace(name, build_accel(scene, parse_structure(name)));
    gpu.emplace(name, gpu::build_accel_gpu(device(), scene, parse_structure(name)));
  }
  // Uploaded once; between frames only their top levels are copied again.
  std::map<std::string, std::unique_ptr<gpu::GpuAccel>> on_device;
  std::map<const Accel*, const gpu::GpuAccel*> resident;
  for (auto& [name, accel] : gpu) {
    on_device[name] = std::make_unique<gpu::GpuAccel>(device(), accel);
    resident[&accel] = on_device[name].get();
  }
  for (int f = 0; f < 3; ++f) {
    INFO("frame " << f);
    pose_scene(scene, f / 2.0);
    for (auto& [name, accel] : cpu)
      if (accel.spec.two_level()) update_top_level(scene, accel);
    for (auto& [name, accel] : gpu)
      if (accel.spec.two_level()) {
        update_top_level(scene, accel);
        on_device[name]->upload_top_level(accel);
      }
    cpu.insert_or_assign("bvh", build_accel(scene, parse_structure("bvh")));  // flat: rebuilt every frame
    gpu.insert_or_assign("bvh", gpu::build_accel_gpu(device(), scene, parse_structure("bvh")));
    const RenderResult c = render(scene, cpu, options);
    const RenderResult g = gpu::render_gpu(device(), scene, gpu, options, {}, &resident);
    for (size_t k = 0; k < c.bounce_images.size(); ++k) {
      INFO("bounce " << k);
      REQUIRE(std::memcmp(c.bounce_images[k].data(), g.bounce_images[k].data(), c.bounce_images[k].size() * sizeof(glm::vec3)) == 0);
    }
    float sum = 0.0f;
    for (const glm::vec3& p : g.total) sum += p.x + p.y + p.z;
    REQUIRE(sum > 0.0f);
  }
}

TEST_CASE("a GPU render of some tiles gives the CPU single render's pixels there bit for bit, black elsewhere", "[gpu]") {
  const Scene cornell = load_scene("builtin:cornell");
  RenderOptions options;
  options.schedule = parse_schedule("bvh,2l-ls:2:6");
  options.width = 37;
  options.height = 21;
  options.spp = 2;
  options.bounces = 2;
  options.seed = 3;
  const std::map<std::string, Accel> cpu_built = build_schedule_structures(cornell, options.schedule);
  const std::map<std::string, Accel> gpu_built = gpu::build_schedule_structures_gpu(device(), cornell, options.schedule);
  const RenderResult single = render(cornell, cpu_built, options);
  const TileGrid grid{options.width, options.height, 8};
  RenderOptions shard = options;
  shard.pixels = tile_pixels(grid, parse_shard("1/3", grid));
  const RenderResult gpu = gpu::render_gpu(device(), cornell, gpu_built, shard);
  std::vector<char> mine(single.total.size(), 0);
  for (uint32_t p : shard.pixels) mine[p] = 1;
  const glm::vec3 zero(0.0f);
  for (size_t p = 0; p < mine.size(); ++p) {
    INFO("pixel " << p);
    REQUIRE(std::memcmp(&gpu.total[p], mine[p] ? &single.total[p] : &zero, sizeof(glm::vec3)) == 0);
    for (size_t k = 0; k < gpu.bounce_images.size(); ++k)
      REQUIRE(std::memcmp(&gpu.bounce_images[k][p], mine[p] ? &single.bounce_images[k][p] : &zero, sizeof(glm::vec3)) == 0);
  }
  REQUIRE(gpu.bounces[0].extension_rays == shard.pixels.size() * size_t(shard.spp));  // camera rays of its pixels only
}

TEST_CASE("a GPU render with the throughput switch gives the CPU's images, counts and decisions bit for bit", "[gpu]") {
  const Scene cornell = load_scene("builtin:cornell");
  RenderOptions options;
  options.schedule = parse_schedule("bvh,f-ls:3:6");
  options.throughput_switch = parse_throughput_switch("0.35:2l-ls:2:6");
  options.width = 40;
  options.height = 28;
  options.spp = 2;
  options.bounces = 3;
  options.seed = 9;
  const auto cpu_built = build_schedule_structures(cornell, options.schedule, paper(), options.throughput_switch);
  std::map<std::string, Accel> gpu_built;
  for (const StructureSpec& spec : render_structures(options))
    gpu_built.emplace(spec.name(), gpu::build_accel_gpu(device(), cornell, spec, paper()));
  const RenderResult cpu = render(cornell, cpu_built, options);
  const RenderResult gpu = gpu::render_gpu(device(), cornell, gpu_built, options);
  AccelOptions reference = paper();  // the device's Line Space counters are the reference kernel's
  reference.traversal = Traversal::Reference;
  const RenderResult cpu_reference =
      render(cornell, build_schedule_structures(cornell, options.schedule, reference, options.throughput_switch), options);
  uint64_t switched = 0;
  for (size_t k = 0; k < cpu.bounce_images.size(); ++k) {
    INFO("bounce " << k);
    REQUIRE(cpu.bounces[k].extension_rays == gpu.bounces[k].extension_rays);
    REQUIRE(cpu.bounces[k].shadow_rays == gpu.bounces[k].shadow_rays);
    REQUIRE(cpu.bounces[k].switched_extension_rays == gpu.bounces[k].switched_extension_rays);
    REQUIRE(cpu.bounces[k].switched_shadow_rays == gpu.bounces[k].switched_shadow_rays);
    REQUIRE(std::memcmp(&cpu_reference.bounces[k].ls, &gpu.bounces[k].ls, sizeof(lsk::LsCounters)) == 0);
    REQUIRE(std::memcmp(&cpu_reference.bounces[k].switched_ls, &gpu.bounces[k].switched_ls, sizeof(lsk::LsCounters)) == 0);
    REQUIRE(std::memcmp(cpu.bounce_images[k].data(), gpu.bounce_images[k].data(), cpu.bounce_images[k].size() * sizeof(glm::vec3)) == 0);
    switched += cpu.bounces[k].switched_extension_rays;
  }
  REQUIRE(switched > 0);  // the switch was in play
  REQUIRE(cpu.bounces[2].switched_ls.lookups > 0);
}
