#include "cpu/app/render_frames.h"

#include "common/base/interrupt.h"
#include "common/base/median.h"
#include "common/base/memory_budget.h"
#include "common/base/system_info.h"
#include "common/base/thread_limit.h"
#include "common/model/animation.h"
#include "common/render/backend.h"
#include "common/render/render_output.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"
#include "cpu/build/top_level_update.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

namespace ls {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

template <typename F>
double timed(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int parse_index(const std::string& field, const std::string& text) {
  int value = 0;
  const char* end = field.data() + field.size();
  const auto [ptr, ec] = std::from_chars(field.data(), end, value);
  if (field.empty() || field[0] < '0' || field[0] > '9' || ec != std::errc() || ptr != end || value > kMaxFrameIndex)
    throw InputError("--frames '" + text + "': frames are integers from 0 to " + std::to_string(kMaxFrameIndex) +
                     ", written A:B (A <= B) or N");
  return value;
}

std::string frame_name(int f) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "frame_%04d", f);
  return buf;
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

// The per-structure figures over the frames done, for the summary and the table's last lines.
struct Series {
  std::string structure, update, flat;
  std::vector<double> update_seconds, flat_seconds;
};

json summary_json(const std::vector<Series>& series) {
  json out = json::array();
  for (const Series& s : series) {
    json e{{"structure", s.structure},
           {"update", s.update},
           {"mean_update_seconds", mean(s.update_seconds)},
           {"median_update_seconds", median(s.update_seconds)}};
    if (!s.flat.empty()) {
      e["flat_structure"] = s.flat;
      if (s.flat_seconds.size() == s.update_seconds.size() && !s.flat_seconds.empty()) {
        e["mean_flat_rebuild_seconds"] = mean(s.flat_seconds);
        e["median_flat_rebuild_seconds"] = median(s.flat_seconds);
        e["flat_over_update"] = median(s.update_seconds) > 0.0 ? median(s.flat_seconds) / median(s.update_seconds) : 0.0;
      }
    }
    out.push_back(e);
  }
  return out;
}

std::string ms(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), seconds < 0.01 ? "%.3f" : "%.1f", seconds * 1e3);
  return buf;
}

}  // namespace

FrameRange parse_frames(const std::string& text) {
  const size_t colon = text.find(':');
  FrameRange r;
  r.first = parse_index(text.substr(0, colon), text);
  r.last = colon == std::string::npos ? r.first : parse_index(text.substr(colon + 1), text);
  if (r.first > r.last) throw InputError("--frames '" + text + "': the first frame is after the last");
  if (r.last - r.first + 1 > kMaxFrames)
    throw InputError("--frames '" + text + "': at most " + std::to_string(kMaxFrames) + " frames per run");
  return r;
}

StructureSpec flat_counterpart(const StructureSpec& spec, const Accel& built) {
  if (spec.budgeted) {
    const std::string reference = built.ls_plan ? built.ls_plan->reference : "";
    return reference.empty() ? StructureSpec{} : flat_counterpart(parse_structure(reference), built);
  }
  StructureSpec flat = spec;
  if (spec.kind == StructureKind::TwoLevelBvh) flat.kind = StructureKind::FlatBvh;
  if (spec.kind == StructureKind::TwoLevelLs) flat.kind = StructureKind::FlatLs;
  return flat;
}

void render_frames(Scene scene, const std::string& scene_spec, const RenderOptions& options,
                   const AccelOptions& accel_options, const FramesOptions& frames, const std::string& out_dir,
                   Backend& backend, const Progress& progress) {
  if (!(frames.fps > 0.0 && frames.fps <= 1000.0))
    throw InputError("--fps " + std::to_string(frames.fps) + " must be in (0, 1000]");
  const SceneRig& rig = scene.rig;
  if (rig.animations.empty() && frames.animation != 0)
    throw InputError(scene_spec + ": --animation " + std::to_string(frames.animation) + ", but the scene has no animation");
  check_render_budget(options.width, options.height, options.bounces, accel_options.limits.max_memory);
  const auto time_of = [&](int f) { return double(f) / frames.fps; };
  // Refuses what cannot be posed (a missing animation, weights channels, a singular pose on any frame)
  // before anything is built or said: posing is cheap beside rendering.
  for (int f = frames.range.last; f >= frames.range.first; --f) {
    if ((f & 63) == 0) throw_if_interrupted();
    pose_scene(scene, time_of(f), frames.animation);
  }
  std::string animation_name;
  double duration = 0.0;
  if (rig.animations.empty()) {
    std::fprintf(stderr, "note: %s has no animation: every frame renders the same pose\n", scene_spec.c_str());
  } else {
    const Animation& a = rig.animations[frames.animation];
    animation_name = a.name;
    duration = a.duration();
    if (rig.animations.size() > 1)
      std::fprintf(stderr, "note: %s has %zu animations; rendering animation %zu '%s' (--animation N picks another)\n",
                   scene_spec.c_str(), rig.animations.size(), frames.animation, a.name.c_str());
    if (time_of(frames.range.last) > duration)
      std::fprintf(stderr, "note: frames after t = %g s (the animation's end) hold its last pose\n", duration);
  }

  // The distinct structures bounces 0..B trace (--throughput-switch's too), in schedule order; the
  // two-level ones built once, here.
  const std::vector<StructureSpec> distinct = render_structures(options);
  std::map<std::string, Accel> built;
  json initial = json::array();
  for (const StructureSpec& spec : distinct)
    if (spec.two_level()) {
      const double s = timed([&] { built.emplace(spec.name(), backend.build(scene, spec, accel_options)); });
      initial.push_back({{"structure", spec.name()}, {"seconds", s}});
    }

  std::vector<Series> series;
  for (const StructureSpec& spec : distinct) {
    Series s;
    s.structure = spec.name();
    s.update = spec.two_level() ? "top-level" : "rebuild";
    if (spec.two_level() && frames.flat_comparison) s.flat = flat_counterpart(spec, built.at(spec.name())).name();
    series.push_back(s);
  }
  const std::string device = backend.device();
  const json header{{"scene", scene_spec},
                    {"animation", {{"index", frames.animation}, {"name", animation_name}, {"duration", duration},
                                   {"channels", rig.animations.empty() ? size_t(0) : rig.animations[frames.animation].channels.size()}}},
                    {"schedule", options.schedule.name()},
                    {"width", options.width},
                    {"height", options.height},
                    {"spp", options.spp},
                    {"bounces", options.bounces},
                    {"seed", options.seed},
                    {"fps", frames.fps},
                    {"first_frame", frames.range.first},
                    {"last_frame", frames.range.last},
                    {"top_level_update", top_level_mode_name(frames.top_level)},
                    {"flat_comparison", frames.flat_comparison},
                    {"device", device.empty() ? "cpu: " + cpu_model() : device},
                    {"threads", thread_count()},
                    {"initial_build", initial}};

  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError("cannot create output folder '" + out_dir + "': " + ec.message());
  const fs::path out(out_dir);
  std::set<std::string> refused;  // flat counterparts over the memory budget: not tried again
  json done = json::array();
  size_t listed = 0;  // frames in the frames.json on disk
  auto listed_at = std::chrono::steady_clock::now();
  const auto write_list = [&](bool complete, bool while_interrupted) {
    json list = header;
    list["frames"] = done;
    list["frames_done"] = done.size();
    list["complete"] = complete;
    list["summary"] = summary_json(series);
    write_json_file((out / "frames.json").string(), list, while_interrupted);
    listed = done.size();
    listed_at = std::chrono::steady_clock::now();
  };
  const int total = frames.range.last - frames.range.first + 1;
  try {
    for (int f = frames.range.first; f <= frames.range.last; ++f) {
      throw_if_interrupted();
      const double t = time_of(f);
      pose_scene(scene, t, frames.animation);

      // Bring every structure to this pose: 2L by its top level, flat from scratch.
      std::map<std::string, double> rebuilt;
      json updates = json::array();
      for (size_t i = 0; i < distinct.size(); ++i) {
        const StructureSpec& spec = distinct[i];
        const std::string name = spec.name();
        double s;
        if (spec.two_level()) {
          s = timed([&] { backend.update_top_level(scene, built.at(name), frames.top_level); });
        } else {
          s = timed([&] { built.insert_or_assign(name, backend.build(scene, spec, accel_options)); });
          rebuilt[name] = s;
        }
        updates.push_back({{"structure", name}, {"update", series[i].update}, {"seconds", s}});
        series[i].update_seconds.push_back(s);
      }
      // What rebuilding the flat counterpart of each 2L structure takes on this pose.
      for (size_t i = 0; i < distinct.size(); ++i) {
        if (series[i].flat.empty()) continue;
        const std::string& flat = series[i].flat;
        json& entry = updates[i];
        entry["flat_structure"] = flat;
        double s = -1.0;
        if (rebuilt.count(flat)) {
          s = rebuilt[flat];
        } else if (!refused.count(flat)) {
          try {
            s = timed([&] { backend.build(scene, parse_structure(flat), accel_options); });
          } catch (const InputError& e) {
            refused.insert(flat);
            std::fprintf(stderr, "note: no flat comparison for %s: %s\n", series[i].structure.c_str(), e.what());
          }
        }
        if (s < 0.0) {
          entry["flat_rebuild_seconds"] = nullptr;
          continue;
        }
        entry["flat_rebuild_seconds"] = s;
        entry["flat_over_update"] = entry["seconds"].get<double>() > 0.0 ? s / entry["seconds"].get<double>() : 0.0;
        series[i].flat_seconds.push_back(s);
      }

      const RenderResult result = backend.render(scene, built, options, progress);
      const std::string name = frame_name(f);
      json frame{{"frame", f},
                 {"time", t},
                 {"dir", name},
                 {"updates", updates},
                 {"render_seconds", result.seconds},
                 {"indirect_rays", result.indirect_rays()},
                 {"indirect_seconds", result.indirect_seconds()},
                 {"indirect_mrays_per_s", result.indirect_mrays_per_s()}};
      RenderReportContext ctx{scene_spec, options.schedule.name(), options.spp, options.seed, &built, device, frame,
                              options.throughput_switch, frames.exposure};
      // A whole frame or none: written aside, renamed when complete.
      const fs::path partial = out / (name + ".partial"), final_dir = out / name;
      fs::remove_all(partial);
      try {
        write_render_outputs(partial.string(), result, ctx);
      } catch (...) {
        fs::remove_all(partial, ec);
        throw;
      }
      fs::remove_all(final_dir);
      fs::rename(partial, final_dir);

      done.push_back(frame);
      // After every frame, but past 100 frames at most once a second (rewriting the whole list after
      // each of 10,000 quick frames would write gigabytes); a stopped run lists its frames below.
      const bool last = f == frames.range.last;
      if (last || done.size() <= 100 || std::chrono::steady_clock::now() - listed_at >= std::chrono::seconds(1))
        write_list(last, false);

      if (!frames.quiet) {
        char lead[96];
        std::snprintf(lead, sizeof(lead), "frame %d [%d/%d] t = %.6g s:", f, f - frames.range.first + 1, total, t);
        std::string line = lead;
        for (const json& u : updates) {
          line += " " + u["structure"].get<std::string>() + " " + (u["update"] == "top-level" ? "top level " : "rebuild ") +
                  ms(u["seconds"].get<double>()) + " ms";
          if (u.contains("flat_rebuild_seconds") && !u["flat_rebuild_seconds"].is_null())
            line += " (" + u["flat_structure"].get<std::string>() + " rebuild " + ms(u["flat_rebuild_seconds"].get<double>()) + " ms)";
          line += ";";
        }
        char tail[96];
        std::snprintf(tail, sizeof(tail), " render %.2f s, indirect %.2f MRays/s", result.seconds, result.indirect_mrays_per_s());
        std::fprintf(stderr, "%s%s\n", line.c_str(), tail);
      }
    }
  } catch (const Interrupted&) {
    if (listed < done.size()) write_list(false, true);  // exactly the whole frames on disk
    throw;
  }

  // The table: one row per frame, update milliseconds per structure and the flat comparison.
  std::printf("wrote %s/frame_%04d .. frame_%04d (total.exr, bounce_K.exr, image.png, report.json) and frames.json\n",
              out_dir.c_str(), frames.range.first, frames.range.last);
  std::printf("%s, %ux%u, %d spp, %d bounces, schedule %s%s%s, %g fps, top-level %s\n", scene_spec.c_str(), options.width,
              options.height, options.spp, options.bounces, options.schedule.name().c_str(), device.empty() ? "" : " on ",
              device.c_str(), frames.fps, top_level_mode_name(frames.top_level));
  std::string head = "frame  t (s)   ";
  for (const Series& s : series) {
    head += " " + s.structure + (s.update == "top-level" ? " top ms" : " rebuild ms");
    if (!s.flat.empty()) head += "  " + s.flat + " rebuild ms";
  }
  head += "  render s  MRays/s";
  std::printf("%s\n", head.c_str());
  for (const json& fr : done) {
    char lead[64];
    std::snprintf(lead, sizeof(lead), "%5d  %-8.4g", fr["frame"].get<int>(), fr["time"].get<double>());
    std::string row = lead;
    for (size_t i = 0; i < series.size(); ++i) {
      const json& u = fr["updates"][i];
      const std::string label = " " + series[i].structure + (series[i].update == "top-level" ? " top ms" : " rebuild ms");
      char cell[64];
      std::snprintf(cell, sizeof(cell), "%*s", int(label.size()), ms(u["seconds"].get<double>()).c_str());
      row += cell;
      if (!series[i].flat.empty()) {
        const std::string flabel = "  " + series[i].flat + " rebuild ms";
        const bool has = u.contains("flat_rebuild_seconds") && !u["flat_rebuild_seconds"].is_null();
        std::snprintf(cell, sizeof(cell), "%*s", int(flabel.size()), has ? ms(u["flat_rebuild_seconds"].get<double>()).c_str() : "-");
        row += cell;
      }
    }
    char end[64];
    std::snprintf(end, sizeof(end), "  %8.2f  %7.2f", fr["render_seconds"].get<double>(), fr["indirect_mrays_per_s"].get<double>());
    std::printf("%s%s\n", row.c_str(), end);
  }
  for (const Series& s : series) {
    std::printf("median per frame: %s %s %s ms", s.structure.c_str(), s.update.c_str(), ms(median(s.update_seconds)).c_str());
    if (!s.flat.empty() && s.flat_seconds.size() == s.update_seconds.size() && !s.flat_seconds.empty())
      std::printf(", %s rebuild %s ms (%.0fx)", s.flat.c_str(), ms(median(s.flat_seconds)).c_str(),
                  median(s.update_seconds) > 0.0 ? median(s.flat_seconds) / median(s.update_seconds) : 0.0);
    std::printf("\n");
  }
}

}  // namespace ls
