// linespace-gpu end to end: bad input exits 2 with a one-line reason (no device or a wrong --device
// included), and its hit files, build report and render equal linespace-cpu's.
#include "common/render/image_output.h"
#include "tests/shard_files.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

using namespace test_support;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return temp_path("gpu_cli_test", name); }

// `env`: assignments put in front of the command, as "A=1 B=2".
Run run(const std::string& program, const std::string& args, const std::string& env = "") {
  return run_program(program, args, "gpu_cli_test", env);
}

size_t line_count(const std::string& s) { return size_t(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST_CASE("linespace-gpu bad input exits 2 with a one-line reason", "[gpu_cli]") {
  fs::create_directories(temp(""));
  std::ofstream(temp("odd.rays"), std::ios::binary) << std::string(33, '\0');
  const std::string cases[] = {
      "build --scene builtin:nope",
      "build --structure octree",
      "build --device no-such-device",
      "build --device 99",
      "build --device ''",  // an unset variable: not "the default device"
      "render --size 0x10 --out " + temp("r").string(),
      "render --schedule bvh,,bvh --size 8x8 --out " + temp("r").string(),
      "trace --rays " + temp("odd.rays").string() + " --hits " + temp("h").string(),
      "bench --structures f-ls:8",
      "frobnicate",
      // The CPU fast path's flags: the device traces with the shared kernels, so they are refused.
      "build --exact-width 4",
      "bench --exact-width 8",
      "render --traversal reference --size 8x8 --out " + temp("r").string(),
  };
  for (const std::string& args : cases) {
    const Run r = run(LINESPACE_GPU, args);
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
  }
}

TEST_CASE("linespace-gpu without any Vulkan driver exits 2 with a one-line reason", "[gpu_cli]") {
  // An ICD list naming no driver file: the loader finds no device.
  const Run r = run(LINESPACE_GPU, "build --scene builtin:cornell", "VK_ICD_FILENAMES=/nonexistent/icd.json VK_DRIVER_FILES=/nonexistent/icd.json");
  INFO(r.err);
  CHECK(r.status == 2);
  CHECK(line_count(r.err) == 1);
  CHECK(r.err.find("Vulkan") != std::string::npos);
  const Run d = run(LINESPACE_GPU, "devices", "VK_ICD_FILENAMES=/nonexistent/icd.json VK_DRIVER_FILES=/nonexistent/icd.json");
  INFO(d.out << d.err);
  CHECK(d.status == 2);
  CHECK(line_count(d.err) == 1);
}

TEST_CASE("linespace-gpu devices names the device and driver that the other commands use", "[gpu_cli]") {
  const Run j = run(LINESPACE_GPU, "devices --json");
  INFO(j.out << j.err);
  REQUIRE(j.status == 0);
  const auto devices = nlohmann::json::parse(j.out).at("devices");
  REQUIRE_FALSE(devices.empty());
  // The default is the device `build` chooses without --device, and it reports it by the same name.
  const Run b = run(LINESPACE_GPU, "build --structure bvh --json");
  REQUIRE(b.status == 0);
  const std::string used = nlohmann::json::parse(b.out).at("device");
  size_t defaults = 0;
  for (const auto& d : devices) {
    const std::string name = d.at("name"), type = d.at("type");
    CHECK(d.at("index") < devices.size());
    CHECK(d.at("api_version").get<std::string>().find('.') != std::string::npos);
    if (!d.at("default")) continue;
    ++defaults;
    CHECK(used.rfind(name + " (" + type + ", Vulkan ", 0) == 0);
    CHECK_FALSE(d.at("driver_name").get<std::string>().empty());  // Vulkan 1.2 drivers, lavapipe too, name themselves
    CHECK(d.at("compute") == true);
    // --device INDEX picks the same one.
    const Run by_index = run(LINESPACE_GPU, "build --structure bvh --json --device " + std::to_string(d.at("index").get<int>()));
    REQUIRE(by_index.status == 0);
    CHECK(nlohmann::json::parse(by_index.out).at("device") == used);
  }
  CHECK(defaults == 1);
  const Run t = run(LINESPACE_GPU, "devices");
  REQUIRE(t.status == 0);
  CHECK(line_count(t.out) == devices.size());
  CHECK(t.out.find("[default]") != std::string::npos);
  CHECK(run(LINESPACE_CPU, "devices").status == 2);  // the CPU program has no devices to list
}

TEST_CASE("linespace-gpu trace writes the hit file linespace-cpu writes", "[gpu_cli]") {
  const std::string rays = temp("diffuse.rays").string();
  REQUIRE(run(LINESPACE_CPU, "rays --scene builtin:cornell --kind diffuse --count 3000 --seed 4 --out " + rays).status == 0);
  for (const char* s : {"bvh", "2l-ls:2:6"}) {
    INFO(s);
    REQUIRE(run(LINESPACE_CPU, std::string("trace --structure ") + s + " --rays " + rays + " --hits " + temp("cpu.hits").string()).status == 0);
    const Run g = run(LINESPACE_GPU, std::string("trace --structure ") + s + " --rays " + rays + " --hits " + temp("gpu.hits").string());
    INFO(g.err);
    REQUIRE(g.status == 0);
    const std::string a = slurp(temp("cpu.hits")), b = slurp(temp("gpu.hits"));
    REQUIRE(a.size() == 3000u * 20u);
    REQUIRE(a == b);
  }
}

TEST_CASE("linespace-gpu build and render report the device and the CPU's sizes", "[gpu_cli]") {
  const Run g = run(LINESPACE_GPU, "build --structure f-ls:3:2 --json");
  const Run c = run(LINESPACE_CPU, "build --structure f-ls:3:2 --json");
  REQUIRE(g.status == 0);
  REQUIRE(c.status == 0);
  const auto jg = nlohmann::json::parse(g.out), jc = nlohmann::json::parse(c.out);
  CHECK_FALSE(jg.at("device").get<std::string>().empty());
  for (const char* key : {"triangles", "nodes", "ls_nodes", "shafts_per_ls", "empty_shafts", "bytes_total", "bytes_ls"})
    CHECK(jg.at(key) == jc.at(key));
  CHECK(jg.at("bytes_wide") == 0);  // no CPU fast path is made for the device
  CHECK(jc.at("bytes_wide") > 0);
  const std::string out = temp("render").string();
  const Run r = run(LINESPACE_GPU, "render --size 16x12 --spp 1 --bounces 1 --quiet --out " + out);
  INFO(r.err);
  REQUIRE(r.status == 0);
  for (const char* f : {"total.exr", "bounce_0.exr", "bounce_1.exr", "image.png", "report.json"}) CHECK(fs::exists(out + "/" + f));
  CHECK_FALSE(nlohmann::json::parse(slurp(out + "/report.json")).at("device").get<std::string>().empty());
}

TEST_CASE("linespace-validate candidates and hits report zero mismatches and exit 0", "[gpu_cli]") {
  const Run c = run(LINESPACE_VALIDATE, "candidates --scene builtin:generated:600:2:1 --structure 2l-ls:2:6 --ls-min-triangles 0");
  INFO(c.out << c.err);
  REQUIRE(c.status == 0);
  CHECK(c.out.find(" 0 mismatches") != std::string::npos);
  const Run h = run(LINESPACE_VALIDATE, "hits --scene builtin:cornell --structure f-ls:3:6 --kind random --count 3000 --any-hit");
  INFO(h.out << h.err);
  REQUIRE(h.status == 0);
  CHECK(h.out.find("3000 compared, 0 mismatches") != std::string::npos);
  for (const char* bad : {"hits --structure octree", "candidates --structure bvh", "candidates --device no-such-device",
                          "hits --offset 1 2", "hits --rays /nonexistent.rays",
                          // nothing to compare: it passed, saying "0 compared"
                          "candidates --scene builtin:cornell --structure f-ls:2:2 --offset 1e30 0 0",
                          "candidates --scene builtin:cornell --structure f-ls:30:2"}) {
    const Run r = run(LINESPACE_VALIDATE, bad);
    INFO(bad << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
  }
}

TEST_CASE("linespace-validate rmse on the GPU gives the CPU's RMSE", "[gpu_cli]") {
  const std::string args = "rmse --size 24x16 --spp 1 --bounces 2 --structures f-ls:3:6,2l-ls:2:6 --out ";
  REQUIRE(run(LINESPACE_VALIDATE, args + temp("rmse_cpu").string() + " --device cpu").status == 0);
  const Run g = run(LINESPACE_VALIDATE, args + temp("rmse_gpu").string() + " --device gpu");
  INFO(g.err);
  REQUIRE(g.status == 0);
  const auto cpu = nlohmann::json::parse(slurp(temp("rmse_cpu") / "rmse.json")).at("rows");
  const auto gpu = nlohmann::json::parse(slurp(temp("rmse_gpu") / "rmse.json")).at("rows");
  REQUIRE(cpu.size() == gpu.size());
  REQUIRE(cpu.size() >= 4u);
  for (size_t i = 0; i < cpu.size(); ++i) {
    CHECK(cpu[i].at("structure") == gpu[i].at("structure"));
    CHECK(cpu[i].at("rmse") == gpu[i].at("rmse"));  // the same images, so exactly the same error
  }
}

TEST_CASE("linespace-gpu render --frames writes the frames linespace-cpu writes, pixel for pixel", "[gpu_cli][animation]") {
  const std::string args = "render --scene builtin:carousel --schedule 2l-bvh,2l-ls:1:2 --size 20x14 --spp 1 --bounces 2 "
                           "--frames 10:12 --no-flat-comparison --quiet --out ";
  const Run c = run(LINESPACE_CPU, args + temp("frames_cpu").string());
  const Run g = run(LINESPACE_GPU, args + temp("frames_gpu").string());
  INFO(c.err << g.err);
  REQUIRE(c.status == 0);
  REQUIRE(g.status == 0);
  for (int f = 10; f <= 12; ++f)
    for (const char* file : {"total.exr", "bounce_0.exr", "bounce_1.exr", "bounce_2.exr"}) {
      const std::string rel = "/frame_00" + std::to_string(f) + "/" + file;
      INFO(rel);
      const ls::Image a = ls::read_image(temp("frames_cpu").string() + rel), b = ls::read_image(temp("frames_gpu").string() + rel);
      REQUIRE(a.pixels.size() == 20u * 14u);
      REQUIRE(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(glm::vec3)) == 0);
    }
  const auto jc = nlohmann::json::parse(slurp(temp("frames_cpu") / "frames.json"));
  const auto jg = nlohmann::json::parse(slurp(temp("frames_gpu") / "frames.json"));
  CHECK(jg["frames_done"] == 3);
  CHECK(jg["device"] != jc["device"]);
  for (size_t i = 0; i < 3; ++i) CHECK(jg["frames"][i]["indirect_rays"] == jc["frames"][i]["indirect_rays"]);
}

TEST_CASE("linespace-gpu shards merged, alone or with a CPU shard, equal linespace-cpu's single render", "[gpu_cli]") {
  using test_support::require_same_render;
  const std::string args = "render --scene builtin:cornell --size 45x29 --spp 2 --bounces 2 --schedule bvh,f-ls:3:6,2l-ls:2:6 "
                           "--tile-size 8 --quiet ";
  fs::remove_all(temp("shards"));
  REQUIRE(run(LINESPACE_CPU, args + "--out " + temp("shards/single").string()).status == 0);
  for (int k = 0; k < 3; ++k) {
    const Run g = run(LINESPACE_GPU, args + "--shard " + std::to_string(k) + "/3 --out " + temp("shards/gpu").string());
    INFO(g.err);
    REQUIRE(g.status == 0);
  }
  REQUIRE(run(LINESPACE_CPU, args + "--shard 0/3 --out " + temp("shards/cpu").string()).status == 0);
  const std::string gpu = temp("shards/gpu").string() + "/partial-shard-";
  Run m = run(LINESPACE_GPU, "merge --out " + temp("shards/merged_gpu").string() + " " + gpu + "0-of-3.exr " + gpu +
                                 "1-of-3.exr " + gpu + "2-of-3.exr");
  INFO(m.err);
  REQUIRE(m.status == 0);
  require_same_render(temp("shards/single"), temp("shards/merged_gpu"), 3, false);
  m = run(LINESPACE_CPU, "merge --out " + temp("shards/merged_mixed").string() + " " + temp("shards/cpu").string() +
                             "/partial-shard-0-of-3.exr " + gpu + "1-of-3.exr " + gpu + "2-of-3.exr");
  INFO(m.err);
  REQUIRE(m.status == 0);
  require_same_render(temp("shards/single"), temp("shards/merged_mixed"), 3, false);
  const auto report = nlohmann::json::parse(slurp(temp("shards/merged_mixed/report.json")));
  CHECK(report.at("device").get<std::string>().find("; ") != std::string::npos);  // both devices named
}

TEST_CASE("linespace-validate policy on the GPU gives the CPU's RMSE and rays on X", "[gpu_cli]") {
  const std::string args = "policy --size 24x16 --spp 1 --bounces 2 --structure f-ls:3:6 --thresholds 0.3,0.6 --out ";
  REQUIRE(run(LINESPACE_VALIDATE, args + temp("policy_cpu").string() + " --device cpu").status == 0);
  const Run g = run(LINESPACE_VALIDATE, args + temp("policy_gpu").string() + " --device gpu");
  INFO(g.err);
  REQUIRE(g.status == 0);
  const auto cpu = nlohmann::json::parse(slurp(temp("policy_cpu") / "policy.json")).at("points");
  const auto gpu = nlohmann::json::parse(slurp(temp("policy_gpu") / "policy.json")).at("points");
  REQUIRE(cpu.size() == 4u);
  REQUIRE(cpu.size() == gpu.size());
  for (size_t i = 0; i < cpu.size(); ++i) {
    CHECK(cpu[i].at("rmse") == gpu[i].at("rmse"));  // the same images
    CHECK(cpu[i].at("rays_on_x") == gpu[i].at("rays_on_x"));  // the same decisions
    CHECK(cpu[i].at("indirect_rays") == gpu[i].at("indirect_rays"));
  }
}
