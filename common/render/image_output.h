// Images through OpenEXR and libpng: linear float EXR, and an sRGB PNG for people to look at.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <map>
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

// A float image of named channels ("total.R", ...), interleaved per pixel in `channels` order, with
// string and int header attributes (a sharded render's partial, render_partial.h).
struct ChannelImage {
  uint32_t width = 0, height = 0;
  std::vector<std::string> channels;
  std::vector<float> data;  // width x height x channels.size()
  std::map<std::string, std::string> strings;
  std::map<std::string, int> ints;
};
// Lossless (zip) EXR, written like write_exr (temporary name, then renamed).
void write_channel_exr(const std::string& path, const ChannelImage& image);
// Reads every channel, and the string and int attributes whose names start with attribute_prefix;
// throws InputError (one line) on a file that is missing, not an image, or truncated.
ChannelImage read_channel_exr(const std::string& path, const std::string& attribute_prefix);

}  // namespace ls
