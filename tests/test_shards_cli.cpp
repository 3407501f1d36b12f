// Sharded renders through linespace-cpu as a scheduler would run them: `render --shard K/N` or
// `--tiles A:B` on each "machine", then `merge`; the merged folder must equal the single render's.
// Bad flags and partials that do not add up to one render exit 2 with a one-line reason.
#include "tests/shard_files.h"

#include <algorithm>
#include <array>

using namespace test_support;
namespace fs = std::filesystem;

namespace {

Run cpu(const std::string& args) { return run_program(LINESPACE_CPU, args, "shards_cli"); }
fs::path temp(const std::string& name) { return temp_path("shards_cli", name); }

// 45 x 29 in tiles of 8: 6 x 4 = 24 tiles, the last column 5 px wide and the last row 5 px high.
std::string render_args(const std::string& spp = "2", const std::string& schedule = "bvh,f-ls:3:6",
                        const std::string& tile_size = "8") {
  return "render --scene builtin:cornell --size 45x29 --bounces 2 --quiet --spp " + spp + " --schedule " + schedule +
         " --tile-size " + tile_size + " ";
}
const std::string kRender = render_args();

void render_ok(const std::string& args, const std::string& base = kRender) {
  const Run r = cpu(base + args);
  INFO(args << "\n" << r.err);
  REQUIRE(r.status == 0);
}

}  // namespace

TEST_CASE("shards by --shard and by uneven --tiles, merged, equal the single render in every file", "[shards_cli]") {
  fs::remove_all(temp(""));
  render_ok("--out " + temp("single").string());
  for (int k = 0; k < 3; ++k) render_ok("--shard " + std::to_string(k) + "/3 --out " + temp("parts").string());
  // The partials name their selection, so shards can share one folder.
  REQUIRE(file_names(temp("parts")).size() == 6);
  Run m = cpu("merge --out " + temp("merged").string() + " " + (temp("parts") / "partial-shard-0-of-3.exr").string() + " " +
              (temp("parts") / "partial-shard-1-of-3.exr").string() + " " + (temp("parts") / "partial-shard-2-of-3.exr").string());
  INFO(m.err);
  REQUIRE(m.status == 0);
  require_same_render(temp("single"), temp("merged"), 3);

  for (const char* range : {"0:1", "1:17", "17:24"}) render_ok(std::string("--tiles ") + range + " --out " + temp("ranges").string());
  m = cpu("merge --out " + temp("merged_ranges").string() + " " + (temp("ranges") / "partial-tiles-17-24.exr").string() + " " +
          (temp("ranges") / "partial-tiles-0-1.exr").string() + " " + (temp("ranges") / "partial-tiles-1-17.exr").string());
  INFO(m.err);
  REQUIRE(m.status == 0);
  require_same_render(temp("single"), temp("merged_ranges"), 3);

  // With the throughput switch: its decisions are per path, so shards make the single run's.
  const std::string policy = "--throughput-switch 0.3:2l-ls:2:6 ";
  render_ok(policy + "--out " + temp("single_policy").string());
  for (int k = 0; k < 2; ++k) render_ok(policy + "--shard " + std::to_string(k) + "/2 --out " + temp("policy").string());
  m = cpu("merge --out " + temp("merged_policy").string() + " " + (temp("policy") / "partial-shard-0-of-2.exr").string() + " " +
          (temp("policy") / "partial-shard-1-of-2.exr").string());
  INFO(m.err);
  REQUIRE(m.status == 0);
  require_same_render(temp("single_policy"), temp("merged_policy"), 2);
  const auto report = nlohmann::json::parse(slurp(temp("merged_policy") / "report.json"));
  REQUIRE(report.at("throughput_switch").at("structure") == "2l-ls:2:6");
  REQUIRE(report.at("per_bounce").at(2).at("switched_rays").get<int>() > 0);

  // A given exposure travels in the partials: the merge exposes the PNG as the single run did.
  const std::string exposure = "--exposure 1.5 ";
  render_ok(exposure + "--out " + temp("single_ev").string());
  for (int k = 0; k < 2; ++k) render_ok(exposure + "--shard " + std::to_string(k) + "/2 --out " + temp("ev").string());
  m = cpu("merge --out " + temp("merged_ev").string() + " " + (temp("ev") / "partial-shard-0-of-2.exr").string() + " " +
          (temp("ev") / "partial-shard-1-of-2.exr").string());
  INFO(m.err);
  REQUIRE(m.status == 0);
  require_same_render(temp("single_ev"), temp("merged_ev"), 2);
  REQUIRE(nlohmann::json::parse(slurp(temp("merged_ev") / "report.json")).at("exposure").at("ev") == 1.5);
  REQUIRE(slurp(temp("single_ev") / "image.png") != slurp(temp("single") / "image.png"));
}

TEST_CASE("bad shard flags and partials of different renders exit 2 with a one-line reason", "[shards_cli]") {
  fs::remove_all(temp(""));
  // The exact BVH only (no Line Space to build): these renders only need to differ in one setting.
  const std::string base = render_args("2", "bvh");
  const fs::path parts = temp("parts");
  for (int k = 0; k < 3; ++k) render_ok("--shard " + std::to_string(k) + "/3 --out " + parts.string(), base);
  render_ok("--tiles 0:1 --out " + parts.string(), base);
  render_ok("--shard 1/3 --out " + temp("spp").string(), render_args("1", "bvh"));
  render_ok("--shard 1/3 --seed 9 --out " + temp("seed").string(), base);
  render_ok("--shard 1/3 --ls-angle 60 --out " + temp("angle").string(), base);  // not the default angle
  render_ok("--shard 1/3 --throughput-switch 0.3:bvh --out " + temp("switch").string(), base);
  render_ok("--shard 1/3 --out " + temp("schedule").string(), render_args("2", "2l-bvh"));
  render_ok("--shard 1/3 --out " + temp("tile").string(), render_args("2", "bvh", "9"));
  render_ok("--shard 1/3 --exposure 2 --out " + temp("exposure").string(), base);
  REQUIRE(cpu("render --scene builtin:generated:500:2:1 --size 45x29 --spp 2 --bounces 2 --schedule bvh "
              "--tile-size 8 --quiet --shard 1/3 --out " + temp("scene").string()).status == 0);
  render_ok("--out " + temp("single").string(), base);
  const fs::path truncated = temp("truncated.exr");
  fs::copy_file(parts / "partial-shard-1-of-3.exr", truncated);
  fs::resize_file(truncated, fs::file_size(truncated) * 2 / 3);

  auto part = [&](const fs::path& dir, const std::string& stem) { return std::string(" ") += (dir / (stem + ".exr")).string(); };
  const std::string s0 = part(parts, "partial-shard-0-of-3"), s1 = part(parts, "partial-shard-1-of-3"),
                    s2 = part(parts, "partial-shard-2-of-3");
  const std::string out = " --out " + temp("refused").string() + " ";
  const std::string merge = "merge";
  const std::array<std::pair<std::string, std::string>, 24> cases = {{
      {kRender + "--shard 3/3" + out, "K must be less than N"},
      {kRender + "--shard 1/0" + out, "N must be at least 1"},
      {kRender + "--shard 25/30" + out, "no tile"},
      {kRender + "--shard one/3" + out, "expected K/N"},
      {kRender + "--shard -1/3" + out, "expected K/N"},
      {kRender + "--tiles 3:2" + out, "A must be less than B"},
      {kRender + "--tiles 5:5" + out, "A must be less than B"},
      {kRender + "--tiles 0:25" + out, "past the last tile"},
      {kRender + "--tiles 0:2 --shard 0/2" + out, "excludes"},
      {render_args("2", "bvh,f-ls:3:6", "0") + "--shard 0/2" + out, "--tile-size"},
      {merge + out + s0 + s1, "tiles 2,5,8,11,14,17,20,23 of the 24 tiles"},
      {merge + out + s0 + s1 + s2 + part(parts, "partial-tiles-0-1"), "tile 0 is in both"},
      {merge + out + s0 + s1 + s1, "tile 1 is in both"},
      {merge + out + s0 + part(temp("spp"), "partial-shard-1-of-3") + s2, "spp is '1'"},
      {merge + out + s0 + part(temp("seed"), "partial-shard-1-of-3") + s2, "seed is '9'"},
      {merge + out + s0 + part(temp("angle"), "partial-shard-1-of-3") + s2, "ls_flags is 'angle=60"},
      {merge + out + s0 + part(temp("schedule"), "partial-shard-1-of-3") + s2, "schedule is '2l-bvh'"},
      {merge + out + s0 + part(temp("switch"), "partial-shard-1-of-3") + s2, "throughput_switch is '0.3:bvh'"},
      {merge + out + s0 + part(temp("tile"), "partial-shard-1-of-3") + s2, "tile_size is '9'"},
      {merge + out + s0 + part(temp("exposure"), "partial-shard-1-of-3") + s2, "exposure is {\"ev\":2.0,\"mode\":\"given\"}"},
      {merge + out + s0 + part(temp("scene"), "partial-shard-1-of-3") + s2, "the scene differs"},
      {merge + out + s0 + " " + (temp("single") / "total.exr").string() + s2, "is not a linespace partial"},
      {merge + out + s0 + " " + truncated.string() + s2, "cannot read"},
      {merge + out, "partials is required"},
  }};
  for (const auto& [args, says] : cases) {
    const Run r = cpu(args);
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.rfind("linespace-cpu: ", 0) == 0);
    CHECK(r.err.find(says) != std::string::npos);
  }
  CHECK(!fs::exists(temp("refused")));
}

// 2l-ls:auto's budget and pilot rays choose each object's D and N: shards planned apart are parts
// of different images (merged, they once made an image equal to neither render).
TEST_CASE("partials of 2l-ls:auto renders with another --ls-budget or --ls-budget-rays are refused", "[shards_cli]") {
  const std::string base = render_args("1", "bvh,2l-ls:auto");
  render_ok("--shard 0/2 --ls-budget 0.5 --out " + temp("plan_a").string(), base);
  render_ok("--shard 1/2 --ls-budget 0.5 --out " + temp("plan_a").string(), base);
  render_ok("--shard 1/2 --ls-budget 2 --out " + temp("plan_budget").string(), base);
  render_ok("--shard 1/2 --ls-budget 0.5 --ls-budget-rays 2000 --out " + temp("plan_rays").string(), base);
  const std::string s0 = " " + (temp("plan_a") / "partial-shard-0-of-2.exr").string();
  const Run same = cpu("merge --out " + temp("plan_merged").string() + s0 + " " +
                       (temp("plan_a") / "partial-shard-1-of-2.exr").string());
  INFO(same.err);
  CHECK(same.status == 0);
  for (const char* other : {"plan_budget", "plan_rays"}) {
    const Run r = cpu("merge --out " + temp("plan_refused").string() + s0 + " " +
                      (temp(other) / "partial-shard-1-of-2.exr").string());
    INFO(other << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(r.err.find("ls_flags is") != std::string::npos);
    CHECK(r.err.find(std::string(other) == "plan_budget" ? "ls_budget=2000000" : "ls_budget_rays=2000") != std::string::npos);
  }
  CHECK(!fs::exists(temp("plan_refused")));
}
