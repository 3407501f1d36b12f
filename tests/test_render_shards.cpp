// Sharded rendering against the single render: tiles cover the image exactly once, renders of tile
// subsets put together equal the single render bit for bit (images, ray counts, Line Space counters),
// partials survive the EXR round trip, and merge refuses what does not add up to one render.
#include "common/render/image_output.h"
#include "common/render/merge_partials.h"
#include "common/render/render_partial.h"
#include "common/render/render_shards.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/render/path_tracer.h"
#include "scenes/load_scene.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <random>
#include <unistd.h>

using namespace ls;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("linespace_shards_test_" + std::to_string(getpid())) / name;
}

bool same_bits(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0;
}

bool same_counters(const lsk::LsCounters& a, const lsk::LsCounters& b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

// 37 x 23 in tiles of 8: 5 x 3 tiles, the last column 5 px wide and the last row 7 px high.
RenderOptions small_render() {
  RenderOptions o;
  o.schedule = parse_schedule("bvh,f-ls:3:6,2l-ls:2:4");
  o.width = 37;
  o.height = 23;
  o.spp = 2;
  o.bounces = 2;
  o.seed = 5;
  return o;
}

AccelOptions paper() {
  AccelOptions a;
  a.ls.min_triangles = 0;  // more Line Space nodes on cornell, so the counters are not all zero
  return a;
}

struct Fixture {
  Scene scene = load_scene("builtin:cornell");
  RenderOptions options = small_render();
  std::map<std::string, Accel> built = build_schedule_structures(scene, options.schedule, paper());
  RenderResult full = render(scene, built, options);
  TileGrid grid{options.width, options.height, 8};

  RenderResult shard(const TileSet& tiles) {
    RenderOptions o = options;
    o.pixels = tile_pixels(grid, tiles);
    return render(scene, built, o);
  }
  RenderReportContext context() const { return RenderReportContext{"builtin:cornell", options.schedule.name(), options.spp, options.seed, &built, "", nullptr, ThroughputSwitch{}, ExposureRequest{}}; }
  // Writes the partial of `choice` into dir and returns its EXR path.
  std::string write(const ShardChoice& choice, const fs::path& dir, RenderOptions o) {
    o.pixels = tile_pixels(choice.grid, choice.tiles);
    const RenderResult r = render(scene, built, o);
    RenderReportContext c = context();
    c.spp = o.spp;
    c.seed = o.seed;
    return write_shard_outputs(dir.string(), choice, scene, r, c, paper().ls, o.lookup, paper().plan) + ".exr";
  }
  std::string write(const ShardChoice& choice, const fs::path& dir) { return write(choice, dir, options); }
};

}  // namespace

TEST_CASE("tiles cover every pixel exactly once, row-major, the last ones cut by the border", "[shards]") {
  for (const auto& [w, h, s] : {std::tuple{37u, 23u, 8u}, {32u, 32u, 32u}, {5u, 3u, 16u}, {1u, 1u, 1u}, {64u, 10u, 7u}}) {
    const TileGrid grid{w, h, s};
    INFO(w << "x" << h << " tiles of " << s);
    std::vector<int> seen(size_t(w) * h, 0);
    for (uint32_t t = 0; t < grid.count(); ++t) {
      const uint32_t x0 = (t % grid.columns()) * s, y0 = (t / grid.columns()) * s;
      const std::vector<uint32_t> px = tile_pixels(grid, {t});
      REQUIRE(px.size() == size_t(std::min(s, w - x0)) * std::min(s, h - y0));
      for (uint32_t p : px) {
        REQUIRE(p % w >= x0);
        REQUIRE(p % w < x0 + s);
        REQUIRE(p / w >= y0);
        REQUIRE(p / w < y0 + s);
        ++seen[p];
      }
    }
    for (int n : seen) REQUIRE(n == 1);
    std::vector<uint32_t> all(size_t(w) * h);
    for (uint32_t p = 0; p < all.size(); ++p) all[p] = p;
    REQUIRE(tile_pixels(grid, all_tiles(grid)) == all);
  }
}

TEST_CASE("tile ranges (--tiles A:B) and shards (--shard K/N) select what they say and refuse what the image cannot have", "[shards]") {
  const TileGrid grid{37, 23, 8};  // 15 tiles
  REQUIRE(parse_tile_range("0:3", grid) == TileSet{0, 1, 2});
  REQUIRE(parse_tile_range("14:15", grid) == TileSet{14});
  REQUIRE(parse_shard("1/4", grid) == TileSet{1, 5, 9, 13});
  REQUIRE(parse_shard("0/1", grid) == all_tiles(grid));
  std::vector<int> seen(15, 0);
  for (int k = 0; k < 7; ++k)
    for (uint32_t t : parse_shard(std::to_string(k) + "/7", grid)) ++seen[t];
  for (int n : seen) REQUIRE(n == 1);
  for (const char* bad : {"3:3", "4:2", "0:16", "a:b", "-1:2", "1:", ":2", "1:2:3", "", "1 :2", "0x1:2", "01:2", "0:02"})
    REQUIRE_THROWS_AS(parse_tile_range(bad, grid), InputError);
  for (const char* bad : {"3/3", "4/3", "0/0", "1/x", "15/16", "", "1/", "/2", "-1/2", "1/2/3", "01/3", "1/03", "00/3"})
    REQUIRE_THROWS_AS(parse_shard(bad, grid), InputError);
  REQUIRE_THROWS_AS(choose_tiles("0:2", "0/2", 8, 37, 23), InputError);
  REQUIRE_FALSE(choose_tiles("", "", 8, 37, 23).sharded());
  REQUIRE(choose_tiles("", "2/3", 8, 37, 23).tiles == parse_shard("2/3", grid));
}

TEST_CASE("tile lists survive their text form, and malformed lists are refused", "[shards]") {
  std::mt19937 rng(11);
  for (int round = 0; round < 200; ++round) {
    TileSet t;
    for (uint32_t i = 0; i < 60; ++i)
      if (rng() % 3 == 0) t.push_back(i);
    REQUIRE(parse_tile_ranges_text(tile_ranges_text(t), 60) == t);
  }
  REQUIRE(tile_ranges_text({0, 1, 2, 3, 8, 10, 11, 12}) == "0-3,8,10-12");
  for (const char* bad : {"3,2", "1,1", "2-2", "4-1", "1,", ",1", "x", "1-", "0-60", "60", "1,,2"})
    REQUIRE_THROWS_AS(parse_tile_ranges_text(bad, 60), InputError);
}

TEST_CASE("renders of tile subsets equal the single render in their tiles bit for bit and are black elsewhere", "[shards]") {
  Fixture f;
  RenderResult sum;
  std::vector<uint64_t> rays(f.full.bounces.size(), 0);
  std::vector<lsk::LsCounters> counters(f.full.bounces.size(), lsk::LsCounters{});
  uint64_t dropped = 0;
  for (int k = 0; k < 3; ++k) {
    const TileSet tiles = parse_shard(std::to_string(k) + "/3", f.grid);
    const RenderResult part = f.shard(tiles);
    std::vector<char> mine(size_t(f.options.width) * f.options.height, 0);
    for (uint32_t p : tile_pixels(f.grid, tiles)) mine[p] = 1;
    for (size_t p = 0; p < mine.size(); ++p) {
      INFO("shard " << k << " pixel " << p);
      const glm::vec3 zero(0.0f);
      REQUIRE(std::memcmp(&part.total[p], mine[p] ? &f.full.total[p] : &zero, sizeof(glm::vec3)) == 0);
      for (size_t b = 0; b < part.bounce_images.size(); ++b)
        REQUIRE(std::memcmp(&part.bounce_images[b][p], mine[p] ? &f.full.bounce_images[b][p] : &zero, sizeof(glm::vec3)) == 0);
    }
    for (size_t b = 0; b < part.bounces.size(); ++b) {
      rays[b] += part.bounces[b].extension_rays + part.bounces[b].shadow_rays;
      add_counters(counters[b], part.bounces[b].ls);
    }
    dropped += part.dropped_samples;
  }
  for (size_t b = 0; b < f.full.bounces.size(); ++b) {
    INFO("bounce " << b);
    REQUIRE(rays[b] == f.full.bounces[b].extension_rays + f.full.bounces[b].shadow_rays);
    REQUIRE(same_counters(counters[b], f.full.bounces[b].ls));
  }
  REQUIRE(f.full.bounces[1].ls.lookups > 0);  // the Line Space was in use, so the counters prove something
  REQUIRE(dropped == f.full.dropped_samples);
  // All tiles is the full render.
  REQUIRE(same_bits(f.shard(all_tiles(f.grid)).total, f.full.total));
}

TEST_CASE("partials merged equal the single render bit for bit, by --shard and by uneven --tiles", "[shards]") {
  Fixture f;
  const fs::path dir = temp("merge");
  fs::remove_all(dir);
  for (const std::vector<std::pair<std::string, std::string>>& shards :
       {std::vector<std::pair<std::string, std::string>>{{"", "0/3"}, {"", "1/3"}, {"", "2/3"}},
        {{"0:1", ""}, {"1:9", ""}, {"9:15", ""}},
        {{"", "0/1"}}}) {
    std::vector<std::string> paths;
    for (const auto& [tiles, shard] : shards) paths.push_back(f.write(choose_tiles(tiles, shard, 8, 37, 23), dir));
    const MergedRender m = merge_partials(paths);
    INFO(paths.front());
    REQUIRE(m.result.width == f.full.width);
    REQUIRE(same_bits(m.result.total, f.full.total));
    REQUIRE(m.result.bounce_images.size() == f.full.bounce_images.size());
    for (size_t b = 0; b < f.full.bounce_images.size(); ++b) REQUIRE(same_bits(m.result.bounce_images[b], f.full.bounce_images[b]));
    for (size_t b = 0; b < f.full.bounces.size(); ++b) {
      REQUIRE(m.result.bounces[b].structure == f.full.bounces[b].structure);
      REQUIRE(m.result.bounces[b].extension_rays == f.full.bounces[b].extension_rays);
      REQUIRE(m.result.bounces[b].shadow_rays == f.full.bounces[b].shadow_rays);
      REQUIRE(same_counters(m.result.bounces[b].ls, f.full.bounces[b].ls));
    }
    REQUIRE(m.result.dropped_samples == f.full.dropped_samples);
    REQUIRE(m.report["shards"].size() == paths.size());
    REQUIRE(m.report["indirect"]["rays"].get<uint64_t>() == f.full.indirect_rays());
    REQUIRE(m.report["spp"] == f.options.spp);
    for (const std::string& p : paths) fs::remove(p);
  }
}

TEST_CASE("merge refuses missing and doubled tiles, partials of other renders, non-partials and truncated files", "[shards]") {
  Fixture f;
  const fs::path dir = temp("refuse");
  fs::remove_all(dir);
  const std::string a = f.write(choose_tiles("0:5", "", 8, 37, 23), dir);
  const std::string b = f.write(choose_tiles("5:15", "", 8, 37, 23), dir);
  const std::string overlap = f.write(choose_tiles("4:6", "", 8, 37, 23), dir);
  RenderOptions other = f.options;
  other.spp = 1;
  const std::string spp = f.write(choose_tiles("", "1/2", 8, 37, 23), dir / "spp", other);
  other = f.options;
  other.seed = 6;
  const std::string seed = f.write(choose_tiles("", "1/2", 8, 37, 23), dir / "seed", other);
  const std::string half = f.write(choose_tiles("", "0/2", 8, 37, 23), dir);
  // Another scene: the same render settings on a scene whose content differs.
  Fixture g;
  g.scene.materials[0].albedo.x *= 0.5f;
  const std::string scene = g.write(choose_tiles("", "1/2", 8, 37, 23), dir / "scene");
  const std::string plain = (dir / "plain.exr").string();
  write_exr(plain, Image{37, 23, f.full.total});
  const std::string truncated = (dir / "truncated.exr").string();
  fs::copy_file(a, truncated);
  fs::resize_file(truncated, fs::file_size(truncated) / 2);

  auto refused = [](const std::vector<std::string>& paths, const std::string& says) {
    INFO("expects: " << says);
    try {
      merge_partials(paths);
      FAIL("merged");
    } catch (const InputError& e) {
      const std::string what = e.what();
      INFO(what);
      CHECK(what.find(says) != std::string::npos);
      CHECK(what.find('\n') == std::string::npos);
    }
  };
  REQUIRE_NOTHROW(merge_partials({a, b}));
  refused({a}, "tiles 5-14 of the 15 tiles");
  refused({a, b, overlap}, "tile 4 is in both");
  refused({half, spp}, "spp is '1'");
  refused({half, seed}, "seed is '6'");
  refused({half, scene}, "the scene differs");
  refused({a, plain}, "is not a linespace partial");
  refused({truncated, b}, "cannot read");
  refused({(dir / "nonexistent.exr").string()}, "cannot read");
  refused({}, "no partial");
}
