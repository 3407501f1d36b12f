// Image error as docs/design.md §7 defines it: both linear images are scaled by e = 1 / (99th-percentile
// luminance of the reference), clamped to [0, 1], and the root of the mean squared difference over
// all pixels and RGB channels is taken (comparable in scale to the paper's .002-.044).
#pragma once

#include <glm/glm.hpp>

#include <vector>

namespace ls {

// The scale e of a reference image: 1 / its 99th-percentile luminance (1 when that is not positive).
float exposure_scale(const std::vector<glm::vec3>& reference);

// Throws InputError when the sizes differ.  `scale_from` is the all-exact full image that sets e.
double rmse(const std::vector<glm::vec3>& reference, const std::vector<glm::vec3>& image, float scale);

}  // namespace ls
