// Sharded rendering on the command line (docs/usage.md, "Sharded renders"): `render --tiles A:B` or
// `--shard K/N` renders only those tiles and writes a partial (render_partial.h); `merge` combines
// the partials into the single render's files (merge_partials.h).  Distributing the shards is left to
// an existing scheduler (GNU parallel, a Slurm job array): there is no cluster code here.
#pragma once

#include "common/model/scene.h"
#include "common/render/render_output.h"
#include "common/render/render_types.h"
#include "common/render/tile_selection.h"
#include "common/structure/accel.h"

#include <string>
#include <vector>

namespace ls {

struct ShardChoice {
  std::string selection;  // "--shard 1/3" or "--tiles 0:5"; empty: the whole image, written as usual
  TileGrid grid;
  TileSet tiles;
  bool sharded() const { return !selection.empty(); }
};

// From the values of --tiles and --shard (at most one non-empty) and --tile-size; throws InputError
// (one line) on a value the image's tiles do not allow.
ShardChoice choose_tiles(const std::string& tiles, const std::string& shard, uint32_t tile_size, uint32_t width,
                         uint32_t height);

// Writes DIR/<stem>.exr (the partial) and DIR/<stem>.json (its report: render_report's keys plus
// tile_size, tiles and selection), stem = partial_stem(selection); returns DIR/<stem>.
std::string write_shard_outputs(const std::string& dir, const ShardChoice& choice, const Scene& scene,
                                const RenderResult& result, const RenderReportContext& context, const LsBuildOptions& ls,
                                const LsLookup& lookup, const LsPlanOptions& plan);

// `merge`: merges the partials and writes total.exr, bounce_K.exr, image.png (exposed as the shards
// were asked, from the merged image) and report.json into dir; returns the report.
nlohmann::json merge_render_outputs(const std::string& dir, const std::vector<std::string>& partials);

}  // namespace ls
