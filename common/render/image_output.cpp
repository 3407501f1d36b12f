#include "common/render/image_output.h"

#include "common/base/interrupt.h"
#include "common/base/replace_file.h"
#include "common/model/scene.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>

namespace ls {
namespace {

// The libraries' messages can span lines; the programs print one.
std::string first_line(const std::string& text) {
  const size_t nl = text.find('\n');
  return nl == std::string::npos ? text : text.substr(0, nl);
}

// Writes through `write_temp` to a temporary name beside `path`, then renames it: an interrupted or
// failed write never leaves a half-written file.
template <class WriteTemp>
void write_renamed(const std::string& path, WriteTemp&& write_temp) {
  throw_if_interrupted();  // no output file is begun once an interrupt is pending
  const std::string temp = path + ".partial" + std::filesystem::path(path).extension().string();
  set_partial_file(&temp);
  std::string error;
  try {
    write_temp(temp);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!error.empty()) {
    set_partial_file(nullptr);
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    throw std::runtime_error("cannot write '" + path + "': " + first_line(error));
  }
  replace_file(temp, path);
}

// A float EXR of `channels` interleaved per pixel, lossless zip compression.
void write_float_exr(const std::string& path, uint32_t width, uint32_t height, const std::vector<std::string>& channels,
                     const float* data, const std::map<std::string, std::string>& strings,
                     const std::map<std::string, int>& ints) {
  write_renamed(path, [&](const std::string& temp) {
    Imf::Header header(static_cast<int>(width), static_cast<int>(height));
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& [name, value] : strings) header.insert(name, Imf::StringAttribute(value));
    for (const auto& [name, value] : ints) header.insert(name, Imf::IntAttribute(value));
    Imf::FrameBuffer frame;
    const size_t x_stride = sizeof(float) * channels.size();
    for (size_t c = 0; c < channels.size(); ++c) {
      header.channels().insert(channels[c], Imf::Channel(Imf::FLOAT));
      frame.insert(channels[c], Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(data + c)), x_stride,
                                           x_stride * width));
    }
    Imf::OutputFile file(temp.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(int(height));
  });
}

bool starts_with_bytes(const std::string& path, const unsigned char* magic, size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> head(n);
  return in.read(head.data(), std::streamsize(n)) && std::memcmp(head.data(), magic, n) == 0;
}

bool is_png(const std::string& path) {
  static const unsigned char magic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return starts_with_bytes(path, magic, sizeof magic);
}

// Every channel of an EXR as floats, interleaved in the file's channel order (sorted by name).
ChannelImage read_float_exr(const std::string& path, const std::string& attribute_prefix, const std::string& what) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError("cannot read " + what + "'" + path + "': it is a directory");
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError("cannot read " + what + "'" + path + "': no such file");
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    const long long w = (long long)window.max.x - window.min.x + 1, h = (long long)window.max.y - window.min.y + 1;
    if (w <= 0 || h <= 0 || w > (1 << 20) || h > (1 << 20))
      throw InputError("cannot read " + what + "'" + path + "': not a 2D image");
    ChannelImage image;
    image.width = uint32_t(w);
    image.height = uint32_t(h);
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) image.channels.push_back(it.name());
    if (image.channels.empty()) throw InputError("cannot read " + what + "'" + path + "': the image has no channel");
    for (auto it = header.begin(); it != header.end(); ++it) {
      const std::string name = it.name();
      if (name.rfind(attribute_prefix, 0) != 0) continue;
      if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) image.strings[name] = s->value();
      else if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&it.attribute())) image.ints[name] = i->value();
    }
    const size_t n = image.channels.size();
    image.data.resize(size_t(w) * size_t(h) * n);
    // The slices' base points at pixel (0, 0) of the window's coordinates.
    char* base = reinterpret_cast<char*>(image.data.data()) -
                 (ptrdiff_t(window.min.x) + ptrdiff_t(window.min.y) * ptrdiff_t(w)) * ptrdiff_t(sizeof(float) * n);
    Imf::FrameBuffer frame;
    for (size_t c = 0; c < n; ++c)
      frame.insert(image.channels[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), sizeof(float) * n, sizeof(float) * n * size_t(w)));
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    return image;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError("cannot read " + what + "'" + path + "': " + first_line(e.what()));
  }
}

Image read_png(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  auto fail = [&]() {
    const std::string message = png.message;
    png_image_free(&png);
    return InputError("cannot read image '" + path + "': " + first_line(message));
  };
  if (!png_image_begin_read_from_file(&png, path.c_str())) throw fail();
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> bytes(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, bytes.data(), 0, nullptr)) throw fail();
  Image image;
  image.width = png.width;
  image.height = png.height;
  image.pixels.resize(size_t(png.width) * png.height);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = glm::vec3(bytes[3 * i], bytes[3 * i + 1], bytes[3 * i + 2]) / 255.0f;
  return image;
}

float srgb(float linear) {
  const float x = std::clamp(linear, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

void write_exr(const std::string& path, const Image& image) {
  write_float_exr(path, image.width, image.height, {"R", "G", "B"}, &image.pixels.data()->x, {}, {});
}

void write_png(const std::string& path, const Image& image, float exposure) {
  std::vector<uint8_t> bytes(image.pixels.size() * 3);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const float v = image.pixels[i][c] * exposure;
      bytes[3 * i + size_t(c)] = uint8_t(std::lround(255.0f * srgb(std::isfinite(v) ? v : 0.0f)));
    }
  write_renamed(path, [&](const std::string& temp) {
    png_image png{};
    png.version = PNG_IMAGE_VERSION;
    png.width = image.width;
    png.height = image.height;
    png.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&png, temp.c_str(), 0, bytes.data(), 0, nullptr)) {
      const std::string message = png.message;
      png_image_free(&png);
      throw std::runtime_error(message);
    }
  });
}

void write_channel_exr(const std::string& path, const ChannelImage& image) {
  if (image.data.size() != size_t(image.width) * image.height * image.channels.size())
    throw std::runtime_error("cannot write '" + path + "': pixel data does not match its size and channels");
  write_float_exr(path, image.width, image.height, image.channels, image.data.data(), image.strings, image.ints);
}

ChannelImage read_channel_exr(const std::string& path, const std::string& attribute_prefix) {
  return read_float_exr(path, attribute_prefix, "");
}

Image read_image(const std::string& path) {
  if (is_png(path)) return read_png(path);
  const ChannelImage exr = read_float_exr(path, "\n", "image ");  // no attribute name starts with a newline
  // R, G and B where the file has them (EXR sorts channels by name), else its first three.
  std::vector<size_t> rgb;
  for (const char* name : {"R", "G", "B"}) {
    const auto it = std::find(exr.channels.begin(), exr.channels.end(), name);
    if (it != exr.channels.end()) rgb.push_back(size_t(it - exr.channels.begin()));
  }
  if (rgb.size() != 3) {
    if (exr.channels.size() < 3) throw InputError("image '" + path + "' has fewer than 3 channels");
    rgb = {0, 1, 2};
  }
  Image image;
  image.width = exr.width;
  image.height = exr.height;
  image.pixels.resize(size_t(exr.width) * exr.height);
  const size_t n = exr.channels.size();
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = glm::vec3(exr.data[i * n + rgb[0]], exr.data[i * n + rgb[1]], exr.data[i * n + rgb[2]]);
  return image;
}

}  // namespace ls
