// What the sharded-render tests compare: the files of two render folders, EXR pixels bit for bit
// (headers carry a DateTime, so the files' bytes differ between runs), PNG bytes, and the report's
// ray counts and Line Space counters.
#pragma once

#include "common/render/image_output.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <set>
#include <string>

namespace test_support {

inline std::set<std::string> file_names(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

inline void require_same_exr_pixels(const std::filesystem::path& a, const std::filesystem::path& b) {
  INFO(a.string() << " against " << b.string());
  const ls::ChannelImage x = ls::read_channel_exr(a.string(), "linespace:"), y = ls::read_channel_exr(b.string(), "linespace:");
  REQUIRE(x.width == y.width);
  REQUIRE(x.height == y.height);
  REQUIRE(x.channels == y.channels);
  REQUIRE(x.data.size() == y.data.size());
  REQUIRE(std::memcmp(x.data.data(), y.data.data(), x.data.size() * sizeof(float)) == 0);
}

// `merged` holds exactly the files of `single`, with the same images and the same rays and counters.
// same_walk false: a shard traced on the device, whose Line Space counters count the lookups of the
// reference kernel's walk, not the CPU fast path's (the hits, and so the images, are the same).
inline void require_same_render(const std::filesystem::path& single, const std::filesystem::path& merged, size_t shards,
                                bool same_walk = true) {
  REQUIRE(file_names(single) == file_names(merged));
  for (const std::string& name : file_names(single)) {
    if (name.size() > 4 && name.substr(name.size() - 4) == ".exr") require_same_exr_pixels(single / name, merged / name);
  }
  REQUIRE(slurp(single / "image.png") == slurp(merged / "image.png"));
  const auto a = nlohmann::json::parse(slurp(single / "report.json")), b = nlohmann::json::parse(slurp(merged / "report.json"));
  for (const char* key : {"scene", "schedule", "width", "height", "spp", "bounces", "seed", "dropped_samples", "exposure"}) {
    INFO(key);
    REQUIRE(a.at(key) == b.at(key));
  }
  REQUIRE(a.at("indirect").at("rays") == b.at("indirect").at("rays"));
  REQUIRE(a.at("primary").at("rays") == b.at("primary").at("rays"));
  REQUIRE(a.at("per_bounce").size() == b.at("per_bounce").size());
  for (size_t k = 0; k < a.at("per_bounce").size(); ++k)
    for (const auto& [key, value] : a.at("per_bounce")[k].items()) {
      if (key.find("seconds") != std::string::npos || key == "mrays_per_s") continue;  // timings differ
      if (!same_walk && key.rfind("ls_", 0) == 0) continue;
      INFO("bounce " << k << " " << key);
      REQUIRE(b.at("per_bounce")[k].at(key) == value);
    }
  REQUIRE(b.at("shards").size() == shards);
}

}  // namespace test_support
