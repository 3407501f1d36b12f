// `merge --out DIR PARTIAL...`: combines the partials of one sharded render (render_partial.h) into
// exactly the files the single render writes (render_output.h).  Every pixel is copied from the one
// partial whose tiles hold it, so the images equal the single run's bit for bit (tile_selection.h
// says why tiles make that possible).  Needs no scene and no device.
//
// Refused, with a one-line reason (InputError): a file that cannot be read or is not a partial,
// partials of different renders (the attribute that differs is named: scene fingerprint, schedule,
// spp, bounces, seed, size, tile size, Line Space flags, throughput switch, exposure), a tile in two partials, or
// tiles in none.
#pragma once

#include "common/render/exposure.h"
#include "common/render/render_types.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace ls {

struct MergedRender {
  RenderResult result;    // the images as the single render has them; ray counts, seconds, Line Space
                          // counters and dropped samples summed over the shards
  nlohmann::json report;  // the single render's report.json keys (sums; "seconds" is the shards' sum,
                          // not wall time) plus "tile_size" and "shards": file, selection, tiles,
                          // device, threads, seconds and indirect rays/seconds/MRays/s of each
  ExposureRequest exposure;  // the PNG's, as the shards were asked (render --exposure)
};

// Reads the partials one at a time (memory: the merged images and one partial).
MergedRender merge_partials(const std::vector<std::string>& paths);

}  // namespace ls
