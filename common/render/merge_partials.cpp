#include "common/render/merge_partials.h"

#include "common/render/render_output.h"
#include "common/render/render_partial.h"
#include "common/render/render_types.h"

#include <algorithm>

namespace ls {
namespace {

// The attribute in which two partials differ, as one line; empty when they belong to one render.
std::string difference(const Partial& a, const Partial& b) {
  const auto ia = render_identity(a.header), ib = render_identity(b.header);
  for (size_t i = 0; i < ia.size(); ++i) {
    if (ia[i].second == ib[i].second) continue;
    if (ia[i].first == "scene_fingerprint")
      return "the scene differs: " + b.path + " rendered '" + b.header.scene + "' (fingerprint " + ib[i].second +
             "), " + a.path + " '" + a.header.scene + "' (fingerprint " + ia[i].second + ")";
    return ia[i].first + " is '" + ib[i].second + "' in " + b.path + " but '" + ia[i].second + "' in " + a.path;
  }
  return "";
}

// Adds one shard's per-bounce figures (its report) to the merged statistics.
void add_shard_stats(RenderResult& r, const Partial& p) {
  try {
    const nlohmann::json& per_bounce = p.report.at("per_bounce");
    if (per_bounce.size() != r.bounces.size()) throw InputError(p.path + ": linespace:report has the wrong number of bounces");
    for (size_t k = 0; k < r.bounces.size(); ++k) {
      const nlohmann::json& b = per_bounce.at(k);
      BounceStats& s = r.bounces[k];
      s.structure = b.at("structure").get<std::string>();
      s.extension_rays += b.at("extension_rays").get<uint64_t>();
      s.shadow_rays += b.at("shadow_rays").get<uint64_t>();
      s.trace_seconds += b.at("seconds").get<double>();
      add_counters(s.ls, get_ls_counters(b, "ls_"));
      s.switched_extension_rays += b.at("switched_extension_rays").get<uint64_t>();
      s.switched_shadow_rays += b.at("switched_shadow_rays").get<uint64_t>();
      s.switched_seconds += b.at("switched_seconds").get<double>();
      add_counters(s.switched_ls, get_ls_counters(b, "switched_ls_"));
    }
    r.dropped_samples += p.report.at("dropped_samples").get<uint64_t>();
    r.seconds += p.report.at("seconds").get<double>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(p.path + ": linespace:report is incomplete (" + std::string(e.what()) + ")");
  }
}

nlohmann::json shard_entry(const Partial& p) {
  const nlohmann::json& r = p.report;
  return {{"file", p.path},
          {"selection", p.header.selection},
          {"tiles", tile_ranges_text(p.header.tiles)},
          {"tile_count", p.header.tiles.size()},
          {"device", r.value("device", "")},
          {"threads", r.value("threads", 0)},
          {"seconds", r.value("seconds", 0.0)},
          {"indirect", r.value("indirect", nlohmann::json::object())}};
}

}  // namespace

MergedRender merge_partials(const std::vector<std::string>& paths) {
  if (paths.empty()) throw InputError("merge: no partial given");
  MergedRender m;
  RenderResult& r = m.result;
  Partial first;
  std::vector<int> owner;  // per tile: the partial holding it, -1 none yet
  std::vector<std::string> devices;
  nlohmann::json shards = nlohmann::json::array(), structures;
  bool same_threads = true;
  for (size_t i = 0; i < paths.size(); ++i) {
    Partial p = read_partial(paths[i]);
    const TileGrid grid = p.header.grid();
    if (i == 0) {
      r.width = p.header.width;
      r.height = p.header.height;
      r.bounces.resize(size_t(p.header.bounces) + 1);
      r.bounce_images.assign(r.bounces.size(), std::vector<glm::vec3>(size_t(r.width) * r.height, glm::vec3(0.0f)));
      r.total.assign(size_t(r.width) * r.height, glm::vec3(0.0f));
      owner.assign(grid.count(), -1);
      structures = p.report.value("structures", nlohmann::json::array());
      m.exposure = exposure_request_from_json(p.report);
    } else {
      const std::string diff = difference(first, p);
      if (!diff.empty()) throw InputError("merge: not partials of one render: " + diff);
      const ExposureRequest e = exposure_request_from_json(p.report);
      if (e.automatic != m.exposure.automatic || e.ev != m.exposure.ev)
        throw InputError("merge: not partials of one render: exposure is " + exposure_request_json(e).dump() + " in " +
                         p.path + " but " + exposure_request_json(m.exposure).dump() + " in " + paths[0]);
      // Each shard built the structures itself: their build time adds up like the render time.
      const nlohmann::json more = p.report.value("structures", nlohmann::json::array());
      for (nlohmann::json& s : structures)
        for (const nlohmann::json& o : more)
          if (s.value("structure", "") == o.value("structure", "") && s.contains("build_seconds"))
            s["build_seconds"] = s["build_seconds"].get<double>() + o.value("build_seconds", 0.0);
    }
    for (uint32_t t : p.header.tiles) {
      if (owner[t] >= 0)
        throw InputError("merge: tile " + std::to_string(t) + " is in both " + paths[size_t(owner[t])] + " and " +
                         paths[i] + " (every tile must be in exactly one partial)");
      owner[t] = int(i);
    }
    for (uint32_t px : tile_pixels(grid, p.header.tiles)) {
      r.total[px] = p.total[px];
      for (size_t k = 0; k < r.bounce_images.size(); ++k) r.bounce_images[k][px] = p.bounce_images[k][px];
    }
    add_shard_stats(r, p);
    const std::string device = p.report.value("device", "");
    if (std::find(devices.begin(), devices.end(), device) == devices.end()) devices.push_back(device);
    shards.push_back(shard_entry(p));
    same_threads = same_threads && shards.back()["threads"] == shards.front()["threads"];
    if (i == 0) {
      p.bounce_images.clear();  // keep the header and report only
      p.total.clear();
      first = std::move(p);
    }
  }
  TileSet missing;
  for (uint32_t t = 0; t < owner.size(); ++t)
    if (owner[t] < 0) missing.push_back(t);
  if (!missing.empty())
    throw InputError("merge: tile" + std::string(missing.size() == 1 ? " " : "s ") + tile_ranges_text(missing) + " of the " +
                     first.header.grid().describe() + " " + (missing.size() == 1 ? "is" : "are") + " in no partial given");

  std::string device;
  for (const std::string& d : devices) device += (device.empty() ? "" : "; ") + d;
  const RenderReportContext context{first.header.scene, first.header.schedule, first.header.spp, first.header.seed, nullptr,
                                    device, nullptr, ThroughputSwitch{}, ExposureRequest{}};
  m.report = render_report(r, context);
  m.report["structures"] = structures;
  m.report["throughput_switch"] = first.report.value("throughput_switch", nlohmann::json(nullptr));
  m.report["threads"] = same_threads ? shards.front()["threads"] : nlohmann::json(0);
  m.report["tile_size"] = first.header.tile_size;
  m.report["shards"] = shards;
  return m;
}

}  // namespace ls
