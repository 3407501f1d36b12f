// Images through OpenImageIO: linear float EXR, and an sRGB PNG for people to look at.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace ls {

struct Image {
  uint32_t width = 0, height = 0;
  std::vector<glm::vec3> pixels;  // row-major, top row first, linear radiance
};

// Throws std::runtime_error naming the path on failure.  Writes to a temporary name and renames, so
// an interrupted run never leaves a half-written file behind.
void write_exr(const std::string& path, const Image& image);
// Clamps to [0, 1] after multiplying by `exposure`, applies the sRGB transfer curve, 8 bits.
void write_png(const std::string& path, const Image& image, float exposure = 1.0f);
Image read_image(const std::string& path);  // throws InputError

}  // namespace ls
