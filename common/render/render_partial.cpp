#include "common/render/render_partial.h"

#include "common/base/float_text.h"
#include "common/render/image_output.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"

#include <algorithm>

namespace ls {
namespace {

const std::string kPrefix = "linespace:";

std::vector<std::string> channel_names(int bounces) {
  std::vector<std::string> names;
  auto add = [&](const std::string& layer) {
    for (const char* c : {"R", "G", "B"}) names.push_back(layer + "." + c);
  };
  add("total");
  for (int k = 0; k <= bounces; ++k) add("bounce_" + std::to_string(k));
  return names;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> render_identity(const PartialHeader& h) {
  return {{"scene_fingerprint", h.scene_fingerprint},
          {"schedule", h.schedule},
          {"spp", std::to_string(h.spp)},
          {"bounces", std::to_string(h.bounces)},
          {"seed", std::to_string(h.seed)},
          {"width", std::to_string(h.width)},
          {"height", std::to_string(h.height)},
          {"tile_size", std::to_string(h.tile_size)},
          {"ls_flags", h.ls_flags},
          {"throughput_switch", h.throughput_switch}};
}

std::string ls_flags_text(const LsBuildOptions& o, const LsLookup& lookup, const LsPlanOptions& plan) {
  return "angle=" + float_text(lookup.angle_degrees) + " further_rays=" + std::to_string(o.further_rays) +
         " min_triangles=" + std::to_string(o.min_triangles) + " candidates=" + (o.paper_candidates ? "paper" : "compact") +
         " behind=" + ls_behind_name(lookup.behind) + " leave_reach=" + float_text(lookup.leave_reach) +
         " ls_budget=" + std::to_string(plan.budget) + " ls_budget_rays=" + std::to_string(plan.rays);
}

std::string partial_stem(const std::string& selection) {
  std::string s = "partial-";
  for (char c : selection.substr(selection.rfind("--", 0) == 0 ? 2 : 0)) {
    if (c == ' ' || c == ':') s += '-';
    else if (c == '/') s += "-of-";
    else s += c;
  }
  return s;
}

void write_partial(const std::string& path, const PartialHeader& h, const RenderResult& result,
                   const nlohmann::json& report) {
  ChannelImage image;
  image.width = result.width;
  image.height = result.height;
  image.channels = channel_names(h.bounces);
  const size_t pixels = size_t(result.width) * result.height, n = image.channels.size();
  image.data.resize(pixels * n);
  for (size_t p = 0; p < pixels; ++p) {
    float* out = &image.data[p * n];
    for (int c = 0; c < 3; ++c) out[c] = result.total[p][c];
    for (size_t k = 0; k < result.bounce_images.size(); ++k)
      for (int c = 0; c < 3; ++c) out[3 * (k + 1) + size_t(c)] = result.bounce_images[k][p][c];
  }
  image.strings = {{kPrefix + "format", kPartialFormat},
                   {kPrefix + "scene", h.scene},
                   {kPrefix + "scene_fingerprint", h.scene_fingerprint},
                   {kPrefix + "schedule", h.schedule},
                   {kPrefix + "seed", std::to_string(h.seed)},
                   {kPrefix + "ls_flags", h.ls_flags},
                   {kPrefix + "throughput_switch", h.throughput_switch},
                   {kPrefix + "tiles", tile_ranges_text(h.tiles)},
                   {kPrefix + "selection", h.selection},
                   {kPrefix + "report", report.dump()}};
  image.ints = {{kPrefix + "spp", h.spp},
                {kPrefix + "bounces", h.bounces},
                {kPrefix + "width", int(h.width)},
                {kPrefix + "height", int(h.height)},
                {kPrefix + "tile_size", int(h.tile_size)},
                {kPrefix + "tile_count", int(h.grid().count())}};
  write_channel_exr(path, image);
}

Partial read_partial(const std::string& path) {
  const ChannelImage image = read_channel_exr(path, kPrefix);
  const auto format = image.strings.find(kPrefix + "format");
  if (format == image.strings.end())
    throw InputError(path + " is not a linespace partial (no linespace:format attribute); merge takes the .exr files "
                            "that render --shard or --tiles writes");
  if (format->second != kPartialFormat)
    throw InputError(path + ": partial format '" + format->second + "', expected '" + kPartialFormat + "'");
  auto text = [&](const std::string& name) {
    const auto it = image.strings.find(kPrefix + name);
    if (it == image.strings.end()) throw InputError(path + ": the partial's header lacks linespace:" + name);
    return it->second;
  };
  auto number = [&](const std::string& name, int lo, int hi) {
    const auto it = image.ints.find(kPrefix + name);
    if (it == image.ints.end()) throw InputError(path + ": the partial's header lacks linespace:" + name);
    if (it->second < lo || it->second > hi)
      throw InputError(path + ": linespace:" + name + " = " + std::to_string(it->second) + " is out of range");
    return it->second;
  };
  Partial p;
  p.path = path;
  PartialHeader& h = p.header;
  h.scene = text("scene");
  h.scene_fingerprint = text("scene_fingerprint");
  h.schedule = text("schedule");
  h.ls_flags = text("ls_flags");
  h.throughput_switch = text("throughput_switch");
  h.selection = text("selection");
  h.spp = number("spp", 1, 1 << 16);
  h.bounces = number("bounces", 0, 64);
  h.width = uint32_t(number("width", 1, 16384));
  h.height = uint32_t(number("height", 1, 16384));
  h.tile_size = uint32_t(number("tile_size", 1, 16384));
  try {
    const unsigned long long seed = std::stoull(text("seed"));
    if (seed > UINT32_MAX) throw std::out_of_range("seed");
    h.seed = uint32_t(seed);
  } catch (const std::logic_error&) {
    throw InputError(path + ": linespace:seed '" + text("seed") + "' is not a 32-bit unsigned integer");
  }
  if (uint32_t(number("tile_count", 1, INT32_MAX)) != h.grid().count())
    throw InputError(path + ": linespace:tile_count does not match width, height and tile_size");
  try {
    h.tiles = parse_tile_ranges_text(text("tiles"), h.grid().count());
  } catch (const InputError& e) {
    throw InputError(path + ": linespace:tiles: " + e.what());
  }
  if (h.tiles.empty()) throw InputError(path + ": the partial holds no tile");
  if (image.width != h.width || image.height != h.height)
    throw InputError(path + ": the image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                     " but its header says " + std::to_string(h.width) + "x" + std::to_string(h.height));
  // OpenEXR stores channels sorted by name: find each where it lies.
  const std::vector<std::string> expected = channel_names(h.bounces);
  std::vector<size_t> where;
  for (const std::string& name : expected) {
    const auto it = std::find(image.channels.begin(), image.channels.end(), name);
    if (it == image.channels.end() || image.channels.size() != expected.size())
      throw InputError(path + ": the channels are not total and bounce_0.." + std::to_string(h.bounces) + " (R, G, B)");
    where.push_back(size_t(it - image.channels.begin()));
  }
  try {
    p.report = nlohmann::json::parse(text("report"));
  } catch (const nlohmann::json::exception&) {
    throw InputError(path + ": linespace:report is not JSON");
  }
  const size_t pixels = size_t(h.width) * h.height, n = image.channels.size();
  p.total.resize(pixels);
  p.bounce_images.assign(size_t(h.bounces) + 1, std::vector<glm::vec3>(pixels));
  auto layer = [&](const float* in, size_t first) { return glm::vec3(in[where[first]], in[where[first + 1]], in[where[first + 2]]); };
  for (size_t i = 0; i < pixels; ++i) {
    const float* in = &image.data[i * n];
    p.total[i] = layer(in, 0);
    for (size_t k = 0; k < p.bounce_images.size(); ++k) p.bounce_images[k][i] = layer(in, 3 * (k + 1));
  }
  return p;
}

}  // namespace ls
