#include "cpu/app/cli_program.h"

#include "common/base/interrupt.h"
#include "common/base/memory_budget.h"
#include "common/base/progress.h"
#include "common/base/ray_files.h"
#include "common/base/thread_limit.h"
#include "common/base/without_repeats.h"
#include "common/render/backend.h"
#include "common/render/exposure.h"
#include "common/render/render_output.h"
#include "common/render/render_shards.h"
#include "common/render/render_types.h"
#include "common/structure/accel.h"
#include "common/structure/top_level.h"
#include "cpu/app/cli_flags.h"
#include "cpu/app/cli_report.h"
#include "cpu/app/render_frames.h"
#include "cpu/build/build_accel.h"
#include "cpu/trace/ray_generators.h"
#include "scenes/load_scene.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <system_error>

namespace ls {
namespace {

// A hit file of this scene's hits (design.md §9): a miss is t = +inf with both ids 0xFFFFFFFF, a
// hit a finite t and a triangle of one of its instances.  Random bytes of the right size were once
// compared as hits ("100 % hit another triangle").
void check_hits_of_scene(const std::vector<lsk::Hit>& hits, const Scene& scene, const std::string& what) {
  for (size_t i = 0; i < hits.size(); ++i) {
    const lsk::Hit& h = hits[i];
    const bool miss = h.t == std::numeric_limits<float>::infinity();
    const bool ok = miss ? h.instance == lsk::LS_INVALID && h.triangle == lsk::LS_INVALID
                         : std::isfinite(h.t) && h.instance < scene.instances.size() &&
                               h.triangle < scene.meshes[scene.instances[h.instance].mesh].triangles.size();
    if (!ok)
      throw InputError(what + ", hit " + std::to_string(i) + ": t " + std::to_string(h.t) + ", instance " +
                       std::to_string(h.instance) + ", triangle " + std::to_string(h.triangle) +
                       " is neither a miss nor a triangle of this scene");
  }
}

// Every option of every subcommand, with its default.
struct Values {
  std::string device;
  ThreadsFlag threads;
  std::string scene = "builtin:cornell";
  std::string structure = "bvh";
  bool json = false;
  LsFlags ls;
  std::string rays_path, hits_path, against_path;
  bool any_hit = false;
  std::string kind = "diffuse", out_path;
  size_t count = 1000000;
  uint32_t seed = 1;
  std::string schedule = "bvh", size = "512x512", out_dir = "out/render";
  int spp = 16, bounces = 3;
  bool quiet = false;
  std::string exposure = "auto";  // the PNG's (exposure.h)
  std::string frames, top_level = "rebuild";  // render --frames A:B (render_frames.h)
  double fps = 24.0;
  size_t animation = 0;
  bool no_flat_comparison = false;
  std::string structures = "bvh,2l-bvh";
  int repeats = 5;
  std::string bench_kind = "diffuse";
  bool bench_any_hit = false;
  std::string embree_isa = "best";
  uint32_t tile_size = 32;  // sharded renders (render_shards.h)
  std::string tiles, shard;
  std::string throughput_switch;  // "T:STRUCTURE" (throughput_switch.h)
  std::vector<std::string> partials;
};

struct Commands {
  CLI::App* build = nullptr;
  CLI::App* trace = nullptr;
  CLI::App* rays = nullptr;
  CLI::App* render = nullptr;
  CLI::App* bench = nullptr;
  CLI::App* merge = nullptr;
  CLI::App* devices = nullptr;
};

Commands add_commands(CLI::App& app, Values& v, const ProgramInfo& info) {
  app.require_subcommand(1);
  auto common = [&](CLI::App* cmd, bool builds) {
    if (builds) v.ls.add_to(cmd, info.fast_path_flags);
    if (info.device_flag)
      cmd->add_option("--device", v.device, "Vulkan device: index or part of its name (default: discrete GPU first)");
    cmd->add_option("--scene", v.scene, "scene file (.gltf .glb .obj .ply .off .stl) or builtin:NAME")->capture_default_str();
    v.threads.add_to(cmd);
  };
  Commands c;
  c.build = app.add_subcommand("build", "build a structure and print its size and build time");
  common(c.build, true);
  c.build->add_option("--structure", v.structure, "bvh, 2l-bvh, f-ls:D:N or 2l-ls:D:N")->capture_default_str();
  c.build->add_flag("--json", v.json, "machine-readable output");

  c.trace = app.add_subcommand("trace", "trace a ray file, write a hit file");
  common(c.trace, true);
  c.trace->add_option("--structure", v.structure)->capture_default_str();
  c.trace->add_option("--rays", v.rays_path, "ray file (32-byte records)")->required();
  c.trace->add_option("--hits", v.hits_path, "hit file to write (20-byte records)")->required();
  c.trace->add_flag("--any-hit", v.any_hit, "stop at the first hit in [tmin, tmax]");
  c.trace->add_option("--against", v.against_path,
                      "a hit file of the same rays (say, the exact BVH's): count the rays whose hit is another triangle");

  c.rays = app.add_subcommand("rays", "write a ray file (made on the host)");
  common(c.rays, false);
  c.rays->add_option("--kind", v.kind, "primary, diffuse, random or shadow")->capture_default_str();
  c.rays->add_option("--count", v.count)->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 28));
  c.rays->add_option("--seed", v.seed)->capture_default_str();
  c.rays->add_option("--out", v.out_path, "ray file to write")->required();
  c.rays->add_option("--max-memory", v.ls.max_memory_mb, "refuse a ray count estimated above this many MB (0: half of RAM)")
      ->check(finite_range(0.0, 1e9));

  c.render = app.add_subcommand("render", "path trace; write EXRs per bounce, a PNG and report.json");
  common(c.render, true);
  c.render->add_option("--schedule", v.schedule, "structure per bounce, comma-separated, last repeats")->capture_default_str();
  c.render->add_option("--spp", v.spp, "samples per pixel")->capture_default_str()->check(CLI::Range(1, 1 << 16));
  c.render->add_option("--bounces", v.bounces, "indirect bounces after the primary hit")->capture_default_str()->check(CLI::Range(0, 64));
  c.render->add_option("--size", v.size, "WIDTHxHEIGHT")->capture_default_str();
  c.render->add_option("--out", v.out_dir, "output folder")->capture_default_str();
  c.render->add_option("--seed", v.seed)->capture_default_str();
  c.render->add_flag("--quiet", v.quiet, "no progress bar");
  c.render->add_option("--exposure", v.exposure,
                       "the PNG's exposure: auto (the log-average luminance becomes middle grey) or EV, a multiplier of 2^EV; "
                       "EXRs stay linear")->capture_default_str();
  CLI::Option* frames = c.render->add_option(
      "--frames", v.frames, "render frames A..B of the scene's animation (A:B or N) into OUT/frame_NNNN/ and OUT/frames.json");
  c.render->add_option("--fps", v.fps, "frames per second: frame f is posed at t = f / fps")->capture_default_str()->needs(frames);
  c.render->add_option("--animation", v.animation, "which of the scene's animations --frames renders (index)")
      ->capture_default_str()->needs(frames)->check(CLI::Range(0, 1 << 20));  // -1 was read as 2^64 - 1
  c.render->add_flag("--no-flat-comparison", v.no_flat_comparison, "do not time a flat rebuild beside each 2L update")->needs(frames);
  c.render->add_option("--top-level-update", v.top_level, "how 2L structures follow the animation: rebuild or refit their top level")
      ->capture_default_str()->check(CLI::IsMember({"rebuild", "refit"}))->needs(frames);
  c.render->add_option("--throughput-switch", v.throughput_switch,
                       "T:STRUCTURE: paths whose throughput luminance is below T trace that bounce's rays with STRUCTURE");
  c.render->add_option("--tile-size", v.tile_size, "tile edge in pixels for --tiles and --shard")
      ->capture_default_str()->check(CLI::Range(1, 16384));
  // A sequence is sharded by frame ranges (--frames A:B on each machine), not by tiles.
  auto* tiles = c.render->add_option("--tiles", v.tiles, "render only tiles A..B-1 (row-major) and write a partial for merge")
      ->excludes(frames);
  c.render->add_option("--shard", v.shard, "render only the tiles t with t mod N == K and write a partial for merge")
      ->excludes(tiles)->excludes(frames);

  c.merge = app.add_subcommand("merge", "combine the partials of a sharded render into the single render's files");
  c.merge->add_option("--out", v.out_dir, "output folder")->required();
  c.merge->add_option("partials", v.partials, "partial EXRs written by render --shard or --tiles")->required();

  if (info.print_devices) {
    c.devices = app.add_subcommand("devices", "list the Vulkan devices and their drivers; marks the one chosen without --device");
    c.devices->add_flag("--json", v.json, "machine-readable output");
  }

  c.bench = app.add_subcommand("bench", "MRays/s of each structure on the same rays, in one run");
  common(c.bench, true);
  c.bench->add_option("--rays", v.rays_path, "ray file (default: rays made here, see --kind)");
  c.bench->add_option("--kind", v.bench_kind, "rays to make when --rays is not given: diffuse, primary, random, or shadow (any hit)")
      ->capture_default_str()->check(CLI::IsMember({"diffuse", "primary", "random", "shadow"}));
  c.bench->add_flag("--any-hit", v.bench_any_hit, "occlusion queries (implied by --kind shadow)");
  c.bench->add_option("--count", v.count, "rays to make when --rays is not given")->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 28));
  c.bench->add_option("--seed", v.seed)->capture_default_str();
  c.bench->add_option("--structures", v.structures, "comma-separated structures")->capture_default_str();
  c.bench->add_option("--repeat", v.repeats, "timed runs per structure (median reported)")->capture_default_str()->check(CLI::Range(1, 100));
  c.bench->add_flag("--json", v.json, "machine-readable output");
  if (!info.embree_isas.empty())  // the CPU program runs Embree beside its structures
    c.bench->add_option("--embree-isa", v.embree_isa,
                        "Embree's instruction set: best (its own choice for this CPU) or a limit, e.g. sse2 to match "
                        "a portable build")
        ->capture_default_str()->check(CLI::IsMember(info.embree_isas));
  return c;
}

// Rays made on the host (as `rays` writes them), from an exact F-BVH of the scene.
std::vector<lsk::Ray> make_rays(const Scene& scene, const std::string& kind, size_t count, uint32_t seed) {
  const RayKind k = parse_ray_kind(kind);
  const Accel exact = build_accel(scene, parse_structure("bvh"));
  return generate_rays(scene, exact, k, count, seed);
}

RenderOptions render_options(const Values& v) {
  RenderOptions options;
  options.schedule = parse_schedule(v.schedule);
  const Size size = parse_size(v.size);
  options.width = size.width;
  options.height = size.height;
  options.spp = v.spp;
  options.bounces = v.bounces;
  options.seed = v.seed;
  options.lookup = v.ls.lookup();
  if (!v.throughput_switch.empty()) options.throughput_switch = parse_throughput_switch(v.throughput_switch);
  return options;
}

Progress progress_bar(const Values& v) {
  const ProgressLine line("render", "samples", !v.quiet && stderr_is_terminal());
  return [line](int done, int total) { line.update(size_t(done), size_t(total)); };
}

// render --frames: the animation, frame by frame (render_frames.h).
void run_render_frames(const Scene& scene, const Values& v, Backend& backend) {
  FramesOptions frames;
  frames.range = parse_frames(v.frames);
  frames.fps = v.fps;
  frames.animation = v.animation;
  frames.flat_comparison = !v.no_flat_comparison;
  frames.top_level = parse_top_level_mode(v.top_level);
  frames.quiet = v.quiet;
  frames.exposure = parse_exposure(v.exposure);
  render_frames(scene, v.scene, render_options(v), v.ls.options(), frames, v.out_dir, backend, progress_bar(v));
}

void run_render(const Scene& scene, const Values& v, Backend& backend) {
  if (!v.frames.empty()) return run_render_frames(scene, v, backend);
  if (!scene.rig.animations.empty()) {
    bool weights = false;
    for (const Animation& a : scene.rig.animations) weights = weights || a.weight_channels > 0;
    std::fprintf(stderr, "note: %s is animated; a still render does not pose it%s (--frames A:B renders the animation)\n",
                 v.scene.c_str(), weights ? " and ignores its morph-target weight channels" : "");
  }
  RenderOptions options = render_options(v);
  const AccelOptions accel_options = v.ls.options();
  check_render_budget(options.width, options.height, options.bounces, accel_options.limits.max_memory);
  const ShardChoice shard = choose_tiles(v.tiles, v.shard, v.tile_size, options.width, options.height);
  if (shard.sharded()) options.pixels = tile_pixels(shard.grid, shard.tiles);  // a shard: only its tiles
  // What bounces 0..B trace, the switch's structure included: a schedule's entries past --bounces are
  // not built (they were, and could be refused by the memory budget for a render that never used them).
  std::map<std::string, Accel> built;
  for (const StructureSpec& spec : render_structures(options)) built.emplace(spec.name(), backend.build(scene, spec, accel_options));
  const ThroughputSwitch& policy = options.throughput_switch;
  const Progress progress = progress_bar(v);
  const RenderResult result = backend.render(scene, built, options, progress);
  const std::string device = backend.device();
  RenderReportContext ctx{v.scene, options.schedule.name(), v.spp, v.seed, &built, device, nullptr, policy,
                          parse_exposure(v.exposure)};
  if (shard.sharded()) {
    const std::string stem = write_shard_outputs(v.out_dir, shard, scene, result, ctx, accel_options.ls, options.lookup,
                                                 accel_options.plan);
    std::printf("wrote %s.{exr, json} (a partial for merge): %zu of the image's %s\n", stem.c_str(), shard.tiles.size(),
                shard.grid.describe().c_str());
  } else {
    const nlohmann::json report = write_render_outputs(v.out_dir, result, ctx);
    std::printf("wrote %s/{total.exr, bounce_0..%d.exr, image.png, report.json}; PNG exposure %s\n", v.out_dir.c_str(),
                options.bounces, exposure_text(exposure_from_report(report)).c_str());
  }
  std::printf("%s, %ux%u, %d spp, %d bounces, schedule %s%s%s%s%s: %.2f s; indirect %.2f MRays/s (%llu rays in %.3f s)\n",
              v.scene.c_str(), options.width, options.height, v.spp, options.bounces, options.schedule.name().c_str(),
              policy.enabled() ? ", throughput switch " : "", policy.enabled() ? policy.name().c_str() : "",
              device.empty() ? "" : " on ", device.c_str(), result.seconds, result.indirect_mrays_per_s(),
              (unsigned long long)result.indirect_rays(), result.indirect_seconds());
  if (result.dropped_samples)
    std::printf("warning: %llu non-finite contributions were left out\n", (unsigned long long)result.dropped_samples);
}

// --ls-budget belongs to 2l-ls:auto: given without one it would silently do nothing.
void check_budget_flag(const std::vector<StructureSpec>& specs, const Values& v) {
  if (v.ls.ls_budget_mb <= 0.0) return;
  for (const StructureSpec& s : specs)
    if (s.budgeted) return;
  throw InputError("--ls-budget applies to 2l-ls:auto only, and no structure here is 2l-ls:auto");
}

// The rays a command holds, refused over the budget before the scene is loaded or a ray made.
void check_ray_budgets(const Commands& c, const Values& v) {
  const size_t max_memory = v.ls.options().limits.max_memory;
  if (*c.rays) check_ray_budget("rays", "", v.count, 0, max_memory);
  if (*c.trace) check_ray_budget("trace", v.rays_path, 0, v.against_path.empty() ? 1 : 2, max_memory);
  if (*c.bench) check_ray_budget("bench", v.rays_path, v.count, 1, max_memory);
}

void run(const Commands& c, const Values& v, const ProgramInfo& info) {
  const ThreadLimit threads(v.threads.threads);  // first: a bad count is refused before any work
  if (c.devices && *c.devices) {  // no scene, no structure
    info.print_devices(v.json);
    return;
  }
  if (*c.build || *c.trace) check_budget_flag({parse_structure(v.structure)}, v);
  if (*c.render) {
    std::vector<StructureSpec> specs = parse_schedule(v.schedule).per_bounce;
    if (!v.throughput_switch.empty()) specs.push_back(parse_throughput_switch(v.throughput_switch).structure);
    check_budget_flag(specs, v);
    parse_exposure(v.exposure);  // a bad value is refused before any work
  }
  if (*c.bench) check_budget_flag(parse_structure_list(v.structures), v);
  if (*c.merge) {  // files only: no scene, no backend (no device) needed
    const nlohmann::json report = merge_render_outputs(v.out_dir, v.partials);
    std::printf("merged %zu partials into %s/{total.exr, bounce_K.exr, image.png, report.json}; PNG exposure %s\n",
                v.partials.size(), v.out_dir.c_str(), exposure_text(exposure_from_report(report)).c_str());
    return;
  }
  check_ray_budgets(c, v);
  const Scene scene = load_scene(v.scene);
  if (*c.rays) {  // host work only: no backend (no device) needed
    write_rays(v.out_path, make_rays(scene, v.kind, v.count, v.seed));
    std::fprintf(stderr, "wrote %zu %s rays to %s\n", v.count, v.kind.c_str(), v.out_path.c_str());
    return;
  }
  const std::unique_ptr<Backend> backend = info.make_backend(v.device);
  const std::string device = backend->device();
  if (*c.build) {
    backend->print_build(scene, parse_structure(v.structure), v.ls.options(), v.json);
  } else if (*c.trace) {
    // The files first: bad input is refused before a structure is built.
    const std::vector<lsk::Ray> in = read_rays(v.rays_path);
    std::error_code same_error;
    for (const std::string& input : {v.rays_path, v.against_path})
      if (!input.empty() && std::filesystem::equivalent(input, v.hits_path, same_error))
        throw InputError("--hits " + v.hits_path + " is the input file " + input + ": writing it would replace what is read");
    const std::vector<lsk::Hit> against = v.against_path.empty() ? std::vector<lsk::Hit>{} : read_hits(v.against_path);
    if (!v.against_path.empty() && against.size() != in.size())
      throw InputError("--against " + v.against_path + " holds " + std::to_string(against.size()) + " hits for " +
                       std::to_string(in.size()) + " rays: it must be a hit file of the same ray file");
    if (!v.against_path.empty()) check_hits_of_scene(against, scene, "--against " + v.against_path);
    const Accel accel = backend->build(scene, parse_structure(v.structure), v.ls.options());
    lsk::LsCounters counters{};
    std::string timing;
    const std::vector<lsk::Hit> out = backend->trace(accel, v.ls.lookup(), in, v.any_hit, &counters, &timing);
    if (accel.spec.line_space()) print_counters(counters);
    write_hits(v.hits_path, out);
    size_t found = 0;
    for (const lsk::Hit& h : out) found += h.triangle != lsk::LS_INVALID;
    std::fprintf(stderr, "traced %zu rays with %s%s%s: %zu hits%s; wrote %s\n", in.size(), accel.spec.name().c_str(),
                 device.empty() ? "" : " on ", device.c_str(), found, timing.c_str(), v.hits_path.c_str());
    if (!v.against_path.empty()) print_other_hits(out, against, v.against_path);
  } else if (*c.render) {
    run_render(scene, v, *backend);
  } else if (*c.bench) {
    // "bvh,f-bvh" names one structure twice: it is timed once.
    const std::vector<StructureSpec> specs = without_repeats(parse_structure_list(v.structures));
    const std::vector<lsk::Ray> rays = v.rays_path.empty() ? make_rays(scene, v.bench_kind, v.count, v.seed) : read_rays(v.rays_path);
    if (rays.empty()) throw InputError("bench: the ray file holds no rays");
    const bool occlusion = v.bench_any_hit || (v.rays_path.empty() && v.bench_kind == "shadow");
    backend->bench(scene, rays, specs, v.repeats, v.ls.options(), v.ls.lookup(), occlusion, v.embree_isa, v.json);
  }
}

}  // namespace

int run_program(int argc, char** argv, const ProgramInfo& info) {
  install_interrupt_handlers();  // Ctrl-C: stop cleanly, exit 130, no output file half-written
  CLI::App app{info.description};
  Values v;
  const Commands commands = add_commands(app, v, info);
  try {
    app.parse(argc, argv);
    refuse_empty_values(app);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << info.name << ": " << e.what() << " (see --help)\n";
    return 2;
  }
  v.ls.progress = stderr_is_terminal() && !v.quiet;
  try {
    run(commands, v, info);
  } catch (const Interrupted& e) {
    std::cerr << "\n" << info.name << ": " << e.what() << ", stopped (no partially written output file is left)\n";
    return 128 + interrupt_signal();
  } catch (const InputError& e) {
    std::cerr << info.name << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << info.name << ": error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

}  // namespace ls
