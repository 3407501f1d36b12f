// The partial a sharded render writes (`render --shard K/N` or `--tiles A:B`; docs/usage.md "Sharded
// renders"): one lossless float EXR holding the bounce images and the total exactly as the single
// render has them after averaging, zero outside the shard's tiles, with channels total.R/G/B and
// bounce_K.R/G/B.  Its header carries everything `merge` needs, so the EXR alone suffices (the
// report beside it is a copy for people and scripts).  Attributes, all named linespace:NAME:
//   format             "linespace-partial-1"
//   scene              the --scene text (informative: paths differ between machines)
//   scene_fingerprint  16 hex digits of the loaded scene's content (scene_fingerprint.h)
//   schedule, spp, bounces, seed, width, height, tile_size, ls_flags, throughput_switch
//                      the render's settings; ls_flags lists the Line Space flags that change images,
//                      throughput_switch is "T:STRUCTURE" or "off"
//   tile_count         tiles of the whole image
//   tiles              the shard's tiles, as ranges ("0-3,8,11")
//   selection          the flag that chose them ("--shard 1/3")
//   report             the shard's report.json, compact (rays, seconds and Line Space counters per
//                      bounce, dropped samples, device, threads, structures)
#pragma once

#include "common/render/render_types.h"
#include "common/render/tile_selection.h"
#include "common/structure/accel.h"

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace ls {

inline constexpr const char* kPartialFormat = "linespace-partial-1";

struct PartialHeader {
  std::string scene, scene_fingerprint, schedule, ls_flags, throughput_switch = "off", selection;
  int spp = 0, bounces = 0;
  uint32_t seed = 0, width = 0, height = 0, tile_size = 0;
  TileSet tiles;
  TileGrid grid() const { return TileGrid{width, height, tile_size}; }
};

// What must be equal for partials to belong to one render: (attribute, value) in a fixed order.
std::vector<std::pair<std::string, std::string>> render_identity(const PartialHeader& header);

// The Line Space flags that change images, as one text ("angle=45 further_rays=0 ..."): the build's,
// the lookup's and 2l-ls:auto's plan (its budget and pilot rays choose each object's D and N).
std::string ls_flags_text(const LsBuildOptions& options, const LsLookup& lookup, const LsPlanOptions& plan);

// "--shard 1/3" -> "partial-shard-1-of-3", "--tiles 0:5" -> "partial-tiles-0-5": the partial's file
// name without extension, unique per selection so shards can share one folder.
std::string partial_stem(const std::string& selection);

struct Partial {
  std::string path;
  PartialHeader header;
  nlohmann::json report;
  std::vector<std::vector<glm::vec3>> bounce_images;  // bounces + 1, full size
  std::vector<glm::vec3> total;
};

// Writes the partial EXR (temporary name, then renamed: interrupt.h).
void write_partial(const std::string& path, const PartialHeader& header, const RenderResult& result,
                   const nlohmann::json& report);
// Reads and checks one partial; throws InputError with a one-line reason when the file is missing,
// truncated, not a partial (no linespace:format), or its header is incomplete or inconsistent.
Partial read_partial(const std::string& path);

}  // namespace ls
