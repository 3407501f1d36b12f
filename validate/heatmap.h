// Where an approximation errs: a per-pixel heat-map of the error against the reference, on a fixed
// scale so that maps of different structures can be compared, and the three images side by side.
#pragma once

#include "common/render/image_output.h"

#include <string>

namespace ls {

// Per pixel: the root mean square over RGB of the difference of the two images, each scaled by
// `scale` and clamped to [0, 1] as in docs/design.md §7 (so the map's mean square is the RMSE's square).
std::vector<float> pixel_errors(const Image& reference, const Image& image, float scale);

// Colours (inferno-like ramp, black = 0, pale yellow >= max_error), as linear values for write_png.
Image error_heatmap(const Image& reference, const Image& image, float scale, float max_error);

// Writes PREFIX_heatmap.png and PREFIX_side_by_side.png (reference | image | heat-map).
void write_error_images(const std::string& prefix, const Image& reference, const Image& image, float scale,
                        float max_error);

}  // namespace ls
