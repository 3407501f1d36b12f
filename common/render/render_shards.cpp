#include "common/render/render_shards.h"

#include "common/render/merge_partials.h"
#include "common/render/render_partial.h"
#include "common/render/render_types.h"
#include "common/render/scene_fingerprint.h"
#include "common/structure/accel.h"

#include <cstdio>
#include <filesystem>

namespace ls {

ShardChoice choose_tiles(const std::string& tiles, const std::string& shard, uint32_t tile_size, uint32_t width,
                         uint32_t height) {
  if (!tiles.empty() && !shard.empty()) throw InputError("--tiles and --shard choose the tiles two ways: give one");
  if (tile_size < 1) throw InputError("--tile-size must be at least 1");
  ShardChoice c;
  c.grid = TileGrid{width, height, tile_size};
  if (!tiles.empty()) {
    c.selection = "--tiles " + tiles;
    c.tiles = parse_tile_range(tiles, c.grid);
  } else if (!shard.empty()) {
    c.selection = "--shard " + shard;
    c.tiles = parse_shard(shard, c.grid);
  }
  return c;
}

std::string write_shard_outputs(const std::string& dir, const ShardChoice& choice, const Scene& scene,
                                const RenderResult& result, const RenderReportContext& context, const LsBuildOptions& ls,
                                const LsLookup& lookup, const LsPlanOptions& plan) {
  PartialHeader h;
  h.scene = context.scene;
  h.scene_fingerprint = fingerprint_text(scene_fingerprint(scene));
  h.schedule = context.schedule;
  h.ls_flags = ls_flags_text(ls, lookup, plan);
  h.throughput_switch = context.throughput_switch.name();
  h.selection = choice.selection;
  h.spp = context.spp;
  h.bounces = int(result.bounces.size()) - 1;
  h.seed = context.seed;
  h.width = result.width;
  h.height = result.height;
  h.tile_size = choice.grid.tile_size;
  h.tiles = choice.tiles;
  nlohmann::json report = render_report(result, context);
  report["tile_size"] = h.tile_size;
  report["tiles"] = tile_ranges_text(h.tiles);
  report["selection"] = h.selection;
  report["exposure"] = exposure_request_json(context.exposure);  // the merge exposes the whole image
  create_output_folder(dir);
  const std::filesystem::path stem = std::filesystem::path(dir) / partial_stem(choice.selection);
  const std::string exr = stem.string() + ".exr";
  write_partial(exr, h, result, report);
  write_json_file(stem.string() + ".json", report);
  return stem.string();
}

nlohmann::json merge_render_outputs(const std::string& dir, const std::vector<std::string>& partials) {
  const MergedRender m = merge_partials(partials);
  const Exposure exposure = choose_exposure(m.exposure, m.result.total);
  write_render_images(dir, m.result, exposure);
  nlohmann::json report = m.report;
  report["exposure"] = exposure_json(exposure);
  write_json_file((std::filesystem::path(dir) / "report.json").string(), report);
  return report;
}

}  // namespace ls
