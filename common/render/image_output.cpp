#include "common/render/image_output.h"

#include "common/base/interrupt.h"
#include "common/model/scene.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace ls {
namespace {

void write_pixels(const std::string& path, const OIIO::ImageSpec& spec, const void* data) {
  throw_if_interrupted();  // no output file is begun once an interrupt is pending
  const std::string temp = path + ".partial" + std::filesystem::path(path).extension().string();
  auto out = OIIO::ImageOutput::create(temp);
  if (!out) throw std::runtime_error("cannot write '" + path + "': " + OIIO::geterror());
  set_partial_file(&temp);
  if (!out->open(temp, spec) || !out->write_image(spec.format, data) || !out->close()) {
    set_partial_file(nullptr);
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    throw std::runtime_error("cannot write '" + path + "': " + out->geterror());
  }
  std::filesystem::rename(temp, path);
  set_partial_file(nullptr);
}

void write_pixels(const std::string& path, uint32_t width, uint32_t height, OIIO::TypeDesc type, const void* data) {
  OIIO::ImageSpec spec(int(width), int(height), 3, type);
  if (type == OIIO::TypeDesc::FLOAT) spec.attribute("compression", "zip");
  write_pixels(path, spec, data);
}

// OpenImageIO's messages can span lines; the programs print one.
std::string first_line(const std::string& text) {
  const size_t nl = text.find('\n');
  return nl == std::string::npos ? text : text.substr(0, nl);
}

float srgb(float linear) {
  const float x = std::clamp(linear, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

void write_exr(const std::string& path, const Image& image) {
  write_pixels(path, image.width, image.height, OIIO::TypeDesc::FLOAT, image.pixels.data());
}

void write_png(const std::string& path, const Image& image, float exposure) {
  std::vector<uint8_t> bytes(image.pixels.size() * 3);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const float v = image.pixels[i][c] * exposure;
      bytes[3 * i + size_t(c)] = uint8_t(std::lround(255.0f * srgb(std::isfinite(v) ? v : 0.0f)));
    }
  write_pixels(path, image.width, image.height, OIIO::TypeDesc::UINT8, bytes.data());
}

void write_channel_exr(const std::string& path, const ChannelImage& image) {
  if (image.data.size() != size_t(image.width) * image.height * image.channels.size())
    throw std::runtime_error("cannot write '" + path + "': pixel data does not match its size and channels");
  OIIO::ImageSpec spec(int(image.width), int(image.height), int(image.channels.size()), OIIO::TypeDesc::FLOAT);
  spec.channelnames = image.channels;
  spec.attribute("compression", "zip");  // lossless
  for (const auto& [name, value] : image.strings) spec.attribute(name, value);
  for (const auto& [name, value] : image.ints) spec.attribute(name, value);
  write_pixels(path, spec, image.data.data());
}

ChannelImage read_channel_exr(const std::string& path, const std::string& attribute_prefix) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw InputError("cannot read '" + path + "': " + first_line(OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  ChannelImage image;
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth != 1)
    throw InputError("cannot read '" + path + "': not a 2D image");
  image.width = uint32_t(spec.width);
  image.height = uint32_t(spec.height);
  image.channels = spec.channelnames;
  for (const OIIO::ParamValue& p : spec.extra_attribs) {
    const std::string name = p.name().string();
    if (name.rfind(attribute_prefix, 0) != 0) continue;
    if (p.type() == OIIO::TypeString) image.strings[name] = p.get_string();
    else if (p.type() == OIIO::TypeInt) image.ints[name] = p.get_int();
  }
  image.data.resize(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.data.data()))
    throw InputError("cannot read '" + path + "': " + first_line(in->geterror()));
  return image;
}

Image read_image(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw InputError("cannot read image '" + path + "': " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.nchannels < 3) throw InputError("image '" + path + "' has fewer than 3 channels");
  std::vector<float> data(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, data.data())) throw InputError("cannot read image '" + path + "': " + in->geterror());
  Image image;
  image.width = uint32_t(spec.width);
  image.height = uint32_t(spec.height);
  image.pixels.resize(size_t(spec.width) * size_t(spec.height));
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = glm::vec3(data[i * size_t(spec.nchannels)], data[i * size_t(spec.nchannels) + 1],
                                data[i * size_t(spec.nchannels) + 2]);
  return image;
}

}  // namespace ls
