// common/render/image_output.*: EXRs keep every float bit and the partials' attributes, the PNG holds
// the sRGB curve of docs/design.md §6 (checked against libpng's own decoding and a double-precision
// formula written here), and missing, truncated or foreign files are refused with one line.
#include "common/model/scene.h"
#include "common/render/image_output.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <png.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

using namespace ls;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return test_support::temp_path("image_output_test", name); }

// Every float class: signed zeros, denormals, the largest finite, infinities, NaN, ordinary values.
Image odd_floats() {
  const float inf = std::numeric_limits<float>::infinity(), denorm = std::numeric_limits<float>::denorm_min();
  const float values[] = {0.0f, -0.0f, denorm, -denorm, 1e-38f, std::numeric_limits<float>::max(), inf, -inf,
                          std::numeric_limits<float>::quiet_NaN(), 0.1f, 1.0f, 3.14159f, -2.5f, 65504.0f, 1e20f};
  Image image{5, 3, {}};
  for (int i = 0; i < 15; ++i) image.pixels.push_back(glm::vec3(values[i], values[(i + 5) % 15], values[(i + 11) % 15]));
  return image;
}

void require_same_bits(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  REQUIRE(a.size() == b.size());
  REQUIRE(std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::vec3)) == 0);
}

std::string one_line_refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

}  // namespace

TEST_CASE("an EXR keeps every float bit and is written whole or not at all", "[image_output]") {
  fs::create_directories(temp(""));
  const Image image = odd_floats();
  const std::string path = temp("odd.exr").string();
  write_exr(path, image);
  const Image back = read_image(path);
  CHECK(back.width == image.width);
  CHECK(back.height == image.height);
  require_same_bits(back.pixels, image.pixels);
  CHECK_FALSE(fs::exists(path + ".partial.exr"));
  // A folder that does not exist: refused, nothing left behind.
  CHECK_THROWS_WITH(write_exr(temp("no/such/folder/a.exr").string(), image), Catch::Contains("cannot write"));
  CHECK_FALSE(fs::exists(temp("no")));
}

TEST_CASE("a channel EXR keeps its channels by name and its string and int attributes", "[image_output]") {
  fs::create_directories(temp(""));
  ChannelImage image;
  image.width = 3;
  image.height = 2;
  image.channels = {"total.R", "total.G", "total.B", "bounce_0.R", "bounce_0.G", "bounce_0.B", "a"};
  for (size_t i = 0; i < 3 * 2 * image.channels.size(); ++i) image.data.push_back(float(i) * 0.25f - 1.0f);
  image.strings = {{"linespace:report", "{\"a\": [1, 2]}\nsecond line"}, {"linespace:scene", ""}, {"other:thing", "x"}};
  image.ints = {{"linespace:spp", -7}, {"linespace:width", 3}, {"other:n", 5}};
  const std::string path = temp("partial.exr").string();
  write_channel_exr(path, image);
  const ChannelImage back = read_channel_exr(path, "linespace:");
  CHECK(back.width == 3);
  CHECK(back.height == 2);
  REQUIRE(back.channels.size() == image.channels.size());
  // The file sorts channels by name; each channel's values are its own wherever it lands.
  for (size_t c = 0; c < image.channels.size(); ++c) {
    const auto at = size_t(std::find(back.channels.begin(), back.channels.end(), image.channels[c]) - back.channels.begin());
    REQUIRE(at < back.channels.size());
    for (size_t p = 0; p < 6; ++p) CHECK(back.data[p * back.channels.size() + at] == image.data[p * image.channels.size() + c]);
  }
  CHECK(back.strings == std::map<std::string, std::string>{{"linespace:report", "{\"a\": [1, 2]}\nsecond line"}, {"linespace:scene", ""}});
  CHECK(back.ints == std::map<std::string, int>{{"linespace:spp", -7}, {"linespace:width", 3}});
  ChannelImage wrong = image;
  wrong.data.pop_back();
  CHECK_THROWS_WITH(write_channel_exr(temp("wrong.exr").string(), wrong), Catch::Contains("does not match"));
  CHECK_FALSE(fs::exists(temp("wrong.exr")));
}

TEST_CASE("the PNG is the exposed image through the sRGB curve, 8 bits", "[image_output]") {
  fs::create_directories(temp(""));
  Image image{64, 2, {}};
  for (int i = 0; i < 64; ++i) image.pixels.push_back(glm::vec3(float(i) / 63.0f, float(i) / 20.0f - 0.5f, float(i * i) / 3000.0f));
  image.pixels.push_back(glm::vec3(std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f));
  for (int i = 1; i < 64; ++i) image.pixels.push_back(glm::vec3(1e-4f * float(i), 0.0031308f, 0.5f));
  const float exposure = 1.7f;
  const std::string path = temp("image.png").string();
  write_png(path, image, exposure);
  // Decoded by libpng itself, not by the code under test.
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  REQUIRE(png_image_begin_read_from_file(&png, path.c_str()));
  REQUIRE(png.width == 64);
  REQUIRE(png.height == 2);
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> bytes(PNG_IMAGE_SIZE(png));
  REQUIRE(png_image_finish_read(&png, nullptr, bytes.data(), 0, nullptr));
  for (size_t i = 0; i < image.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      double v = double(image.pixels[i][c]) * exposure;
      if (!std::isfinite(v)) v = 0.0;  // NaN and infinities show black
      v = std::min(std::max(v, 0.0), 1.0);
      const double encoded = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
      INFO("pixel " << i << " channel " << c << " linear " << image.pixels[i][c]);
      CHECK(std::abs(double(bytes[3 * i + size_t(c)]) - 255.0 * encoded) <= 0.5001);
    }
  // read_image gives the stored bytes / 255.
  const Image back = read_image(path);
  REQUIRE(back.pixels.size() == image.pixels.size());
  for (size_t i = 0; i < back.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c) CHECK(back.pixels[i][c] == float(bytes[3 * i + size_t(c)]) / 255.0f);
}

TEST_CASE("missing, truncated and foreign image files are refused with one line", "[image_output]") {
  fs::create_directories(temp(""));
  const std::string exr = temp("whole.exr").string(), png = temp("whole.png").string();
  Image image{40, 30, std::vector<glm::vec3>(1200, glm::vec3(0.25f, 0.5f, 0.75f))};
  for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i].x = float(i % 97) / 7.0f;  // less compressible
  write_exr(exr, image);
  write_png(png, image, 1.0f);
  auto truncated = [&](const std::string& from, const std::string& name) {
    const std::string to = temp(name).string();
    fs::copy_file(from, to, fs::copy_options::overwrite_existing);
    fs::resize_file(to, fs::file_size(to) / 2);
    return to;
  };
  std::ofstream(temp("text.exr")) << "not an image\n";
  const std::string cases[] = {temp("missing.exr").string(), truncated(exr, "half.exr"), truncated(png, "half.png"),
                               temp("text.exr").string()};
  for (const std::string& path : cases) {
    const std::string what = one_line_refusal([&] { read_image(path); });
    INFO(what);
    CHECK(what.find(path) != std::string::npos);
    CHECK(what.find('\n') == std::string::npos);
    const std::string what_channels = one_line_refusal([&] { read_channel_exr(path, "linespace:"); });
    INFO(what_channels);
    CHECK(what_channels.find("cannot read") != std::string::npos);
    CHECK(what_channels.find('\n') == std::string::npos);
  }
  CHECK(one_line_refusal([&] { read_channel_exr(png, "linespace:"); }).find("cannot read") != std::string::npos);
}
