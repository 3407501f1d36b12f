// The PNG's exposure through linespace-cpu render (common/render/exposure.h): automatic by default, so
// a dim interior comes out neither black nor white; --exposure EV scales the PNG by 2^EV against the
// linear EXR, which no exposure touches; bad values exit 2 with a one-line reason.
#include "common/render/image_output.h"
#include "tests/gltf_writer.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace test_support;
namespace fs = std::filesystem;

namespace {

fs::path temp(const std::string& name) { return temp_path("exposure_cli", name); }
Run run(const std::string& args) { return run_program(LINESPACE_CPU, args, "exposure_cli"); }

// A closed grey room 12 x 3 x 10 m (walls facing in), one 0.4 m square panel light of radiance 1
// hanging 10 cm below the ceiling, facing down, and a camera inside: the kind of interior whose
// fixed-exposure picture is nearly black.
std::string dim_interior_gltf() {
  using ls_test::Gltf;
  Gltf g;
  const glm::vec3 lo(-6.0f, 0.0f, -5.0f), hi(6.0f, 3.0f, 5.0f);
  std::vector<glm::vec3> room;
  std::vector<uint32_t> room_idx;
  const auto quad = [](std::vector<glm::vec3>& pos, std::vector<uint32_t>& idx, glm::vec3 a, glm::vec3 b, glm::vec3 c,
                       glm::vec3 d) {  // counter-clockwise seen from the side it faces
    const uint32_t base = uint32_t(pos.size());
    pos.insert(pos.end(), {a, b, c, d});
    idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  };
  const glm::vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                          {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
  quad(room, room_idx, c[0], c[1], c[2], c[3]);  // back (z = lo), facing +z
  quad(room, room_idx, c[5], c[4], c[7], c[6]);  // front, facing -z
  quad(room, room_idx, c[4], c[0], c[3], c[7]);  // left, facing +x
  quad(room, room_idx, c[1], c[5], c[6], c[2]);  // right, facing -x
  quad(room, room_idx, c[4], c[5], c[1], c[0]);  // floor, facing +y
  quad(room, room_idx, c[3], c[2], c[6], c[7]);  // ceiling, facing -y
  std::vector<glm::vec3> light;
  std::vector<uint32_t> light_idx;
  const float y = hi.y - 0.1f, h = 0.2f;
  quad(light, light_idx, {-h, y, -h}, {h, y, -h}, {h, y, h}, {-h, y, h});  // facing down
  const int room_pos = g.vec3(room), room_ix = g.indices(room_idx);
  const int light_pos = g.vec3(light), light_ix = g.indices(light_idx);
  const auto prim = [](int pos, int idx, int material) {
    return R"({"primitives":[{"attributes":{"POSITION":)" + std::to_string(pos) + R"(},"indices":)" + std::to_string(idx) +
           R"(,"material":)" + std::to_string(material) + "}]}";
  };
  return g.json(R"("materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.6,0.6,0.6,1]}},)"
                R"({"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1]},"emissiveFactor":[1,1,1]}],)"
                R"("meshes":[)" + prim(room_pos, room_ix, 0) + "," + prim(light_pos, light_ix, 1) + "],"
                R"("cameras":[{"type":"perspective","perspective":{"yfov":1.0,"znear":0.01}}],)"
                R"("nodes":[{"mesh":0},{"mesh":1},{"camera":0,"translation":[0,1.5,4.5]}],"scenes":[{"nodes":[0,1,2]}],"scene":0)");
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

// The PNG's mean over pixels and channels, in 8-bit levels (read_image gives the stored values / 255).
double png_mean(const fs::path& png) {
  const ls::Image image = ls::read_image(png.string());
  double sum = 0.0;
  for (const glm::vec3& p : image.pixels) sum += double(p.r + p.g + p.b);
  return 255.0 * sum / (3.0 * double(image.pixels.size()));
}

nlohmann::json report(const fs::path& dir) {
  std::ifstream f(dir / "report.json");
  return nlohmann::json::parse(f);
}

// The sRGB transfer curve, written out here to check write_png against.
double srgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

}  // namespace

TEST_CASE("render's default exposure shows a dim interior: its PNG's mean is between 60 and 160 of 255", "[exposure_cli]") {
  fs::remove_all(temp(""));
  fs::create_directories(temp(""));
  const fs::path scene = temp("dim_room.gltf");
  write_text(scene, dim_interior_gltf());
  // render's defaults but a smaller image and fewer samples (the exposure is what is tested).
  const std::string args = "render --scene " + scene.string() + " --size 96x64 --spp 4 --quiet --out ";
  const Run automatic = run(args + temp("auto").string());
  INFO(automatic.err);
  REQUIRE(automatic.status == 0);
  const double mean = png_mean(temp("auto") / "image.png");
  INFO("mean " << mean);
  CHECK(mean >= 60.0);
  CHECK(mean <= 160.0);
  const nlohmann::json e = report(temp("auto")).at("exposure");
  CHECK(e.at("mode") == "auto");
  CHECK(e.at("multiplier").get<double>() == Approx(std::exp2(e.at("ev").get<double>())).epsilon(1e-5));
  CHECK(automatic.out.find("PNG exposure auto, EV +") != std::string::npos);

  // The same render at the radiance as it is (EV 0, what render wrote before): nearly black.
  const Run fixed = run(args + temp("ev0").string() + " --exposure 0");
  REQUIRE(fixed.status == 0);
  const double dark = png_mean(temp("ev0") / "image.png");
  INFO("EV 0 mean " << dark);
  CHECK(dark < 30.0);
  CHECK(report(temp("ev0")).at("exposure").at("mode") == "given");
  CHECK(report(temp("ev0")).at("exposure").at("multiplier") == 1.0);
}

TEST_CASE("render --exposure EV scales the PNG by 2^EV against the EXR, and auto makes the log-average luminance 0.18", "[exposure_cli]") {
  fs::remove_all(temp(""));
  const std::string args = "render --scene builtin:cornell --size 40x30 --spp 2 --bounces 2 --quiet --out ";
  for (const char* name : {"auto", "minus2", "plus1"}) {
    const std::string ev = std::string(name) == "auto" ? "auto" : std::string(name) == "minus2" ? "-2" : "+1";
    const Run r = run(args + temp(name).string() + " --exposure " + ev);
    INFO(r.err);
    REQUIRE(r.status == 0);
  }
  const ls::Image exr = ls::read_image((temp("auto") / "total.exr").string());
  // EXRs are linear and unscaled: every exposure writes the same pixels.
  for (const char* name : {"minus2", "plus1"}) REQUIRE(ls::read_image((temp(name) / "total.exr").string()).pixels == exr.pixels);

  // The automatic multiplier from the EXR: 0.18 / the geometric mean of the lit pixels' luminance.
  double log_sum = 0.0;
  size_t lit = 0;
  for (const glm::vec3& p : exr.pixels) {
    const double l = 0.2126 * p.r + 0.7152 * p.g + 0.0722 * p.b;
    if (l > 0.0) {
      log_sum += std::log(l);
      ++lit;
    }
  }
  REQUIRE(lit > 0);
  const double key = 0.18 / std::exp(log_sum / double(lit));
  const nlohmann::json automatic = report(temp("auto")).at("exposure");
  CHECK(automatic.at("multiplier").get<double>() == Approx(key).epsilon(1e-5));

  for (const auto& [name, multiplier] : {std::pair<const char*, double>{"auto", automatic.at("multiplier").get<double>()}, {"minus2", 0.25}, {"plus1", 2.0}}) {
    INFO(name);
    const ls::Image png = ls::read_image((temp(name) / "image.png").string());
    REQUIRE(png.pixels.size() == exr.pixels.size());
    size_t off = 0;
    for (size_t i = 0; i < exr.pixels.size(); ++i)
      for (int c = 0; c < 3; ++c) off += std::abs(double(png.pixels[i][c]) * 255.0 - 255.0 * srgb(exr.pixels[i][c] * multiplier)) > 0.51;
    CHECK(off == 0);
  }
  CHECK(report(temp("minus2")).at("exposure").at("ev") == -2.0);
  CHECK(report(temp("plus1")).at("exposure").at("multiplier") == 2.0);
}

TEST_CASE("render --exposure refuses what is not auto or a number of stops, with exit 2 and a one-line reason", "[exposure_cli]") {
  fs::remove_all(temp(""));
  for (const char* bad : {"abc", "nan", "inf", "-inf", "1e9", "65", "2x", "''", "0x10", "' 1'", "1e", "++1", "+-1"}) {
    const Run r = run("render --scene builtin:cornell --size 8x8 --spp 1 --quiet --exposure " + std::string(bad) + " --out " +
                      temp("bad").string());
    INFO(bad << ": " << r.err);
    CHECK(r.status == 2);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.find("--exposure") != std::string::npos);
  }
  CHECK(!fs::exists(temp("bad")));
}
