// linespace-cpu: the command line of the CPU reference (DESIGN §9).
// Exit status: 0 success, 1 a check failed, 2 bad input or usage (one-line reason on stderr).
#include "accel.h"
#include "cli_flags.h"
#include "cli_report.h"
#include "bench.h"
#include "interrupt.h"
#include "load_scene.h"
#include "memory_budget.h"
#include "path_tracer.h"
#include "ray_files.h"
#include "ray_generators.h"
#include "render_output.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <unistd.h>

namespace {

using namespace ls;

void print_bench(const BenchResult& r, bool json) {
  if (json) {
    nlohmann::json results = nlohmann::json::array();
    for (const BenchEntry& e : r.results) {
      nlohmann::json j{{"structure", e.structure},
                       {"mrays_per_s", e.mrays_per_s},
                       {"ratio_vs_embree", e.ratio_vs_embree},
                       {"bytes", e.bytes},
                       {"build_seconds", e.build_seconds}};
      if (e.structure != "embree") {
        j["traversal"] = "fast";
        j["reference_mrays_per_s"] = e.reference_mrays_per_s;
        j["reference_ratio_vs_embree"] = e.reference_ratio_vs_embree;
        j["ratio_vs_fast_bvh"] = e.ratio_vs_fast_bvh;
        j["bytes_wide"] = e.bytes_wide;
      }
      results.push_back(j);
    }
    std::cout << nlohmann::json{{"rays", r.rays}, {"threads", r.threads}, {"repeats", r.repeats}, {"device", "cpu: " + r.cpu},
                                {"isa", r.isa}, {"wide_width", r.wide_width}, {"any_hit", r.any_hit}, {"results", results}}
                     .dump(2)
              << "\n";
    return;
  }
  std::printf("%zu rays (%s), %d threads, median of %d runs, %s\n", r.rays, r.any_hit ? "any hit" : "closest hit",
              r.threads, r.repeats, r.cpu.c_str());
  std::printf("fast path: %d-wide BVH, %s; reference: the scalar single-source kernels\n", r.wide_width, r.isa.c_str());
  std::printf("%-14s %10s %10s %10s %10s %9s %10s %9s %9s\n", "structure", "fast MR/s", "vs Embree", "vs bvh", "ref MR/s",
              "ref vs E", "fast/ref", "MB", "build s");
  for (const BenchEntry& e : r.results) {
    if (e.structure == "embree") {
      std::printf("%-14s %10.2f %9.2fx %10s %10s %9s %10s %9.2f %9.3f\n", e.structure.c_str(), e.mrays_per_s,
                  e.ratio_vs_embree, "", "", "", "", double(e.bytes) / 1e6, e.build_seconds);
      continue;
    }
    std::printf("%-14s %10.2f %9.2fx %9.2fx %10.2f %8.2fx %9.2fx %9.2f %9.3f\n", e.structure.c_str(), e.mrays_per_s,
                e.ratio_vs_embree, e.ratio_vs_fast_bvh, e.reference_mrays_per_s, e.reference_ratio_vs_embree,
                e.reference_mrays_per_s > 0.0 ? e.mrays_per_s / e.reference_mrays_per_s : 0.0,
                double(e.bytes + e.bytes_wide) / 1e6, e.build_seconds);
  }
}

}  // namespace

int main(int argc, char** argv) {
  install_interrupt_handlers();  // Ctrl-C: stop cleanly, exit 130, no output file half-written
  CLI::App app{"linespace-cpu: exact and Line Space ray tracing, CPU reference"};
  app.require_subcommand(1);
  std::string scene_spec = "builtin:cornell";
  std::string structure = "bvh";
  bool json = false;
  LsFlags ls_flags;

  auto* build = app.add_subcommand("build", "build a structure and print its size and build time");
  ls_flags.add_to(build);
  build->add_option("--scene", scene_spec, "scene file or builtin:NAME")->capture_default_str();
  build->add_option("--structure", structure, "bvh, 2l-bvh, f-ls:D:N or 2l-ls:D:N")->capture_default_str();
  build->add_flag("--json", json, "machine-readable output");

  std::string rays_path, hits_path;
  bool any_hit = false;
  auto* trace = app.add_subcommand("trace", "trace a ray file, write a hit file");
  ls_flags.add_to(trace);
  trace->add_option("--scene", scene_spec)->capture_default_str();
  trace->add_option("--structure", structure)->capture_default_str();
  trace->add_option("--rays", rays_path, "ray file (32-byte records)")->required();
  trace->add_option("--hits", hits_path, "hit file to write (20-byte records)")->required();
  trace->add_flag("--any-hit", any_hit, "stop at the first hit in [tmin, tmax]");

  std::string kind = "diffuse", out_path;
  size_t count = 1000000;
  uint32_t seed = 1;
  auto* rays = app.add_subcommand("rays", "write a ray file");
  rays->add_option("--scene", scene_spec)->capture_default_str();
  rays->add_option("--kind", kind, "primary, diffuse, random or shadow")->capture_default_str();
  rays->add_option("--count", count)->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 28));
  rays->add_option("--seed", seed)->capture_default_str();
  rays->add_option("--out", out_path, "ray file to write")->required();

  std::string schedule = "bvh", size_text = "512x512", out_dir = "out/render";
  int spp = 16, bounces = 3;
  bool quiet = false;
  auto* render_cmd = app.add_subcommand("render", "path trace; write EXRs per bounce, a PNG and report.json");
  ls_flags.add_to(render_cmd);
  render_cmd->add_option("--scene", scene_spec)->capture_default_str();
  render_cmd->add_option("--schedule", schedule, "structure per bounce, comma-separated, last repeats")->capture_default_str();
  render_cmd->add_option("--spp", spp, "samples per pixel")->capture_default_str()->check(CLI::Range(1, 1 << 16));
  render_cmd->add_option("--bounces", bounces, "indirect bounces after the primary hit")->capture_default_str()->check(CLI::Range(0, 64));
  render_cmd->add_option("--size", size_text, "WIDTHxHEIGHT")->capture_default_str();
  render_cmd->add_option("--out", out_dir, "output folder")->capture_default_str();
  render_cmd->add_option("--seed", seed)->capture_default_str();
  render_cmd->add_flag("--quiet", quiet, "no progress bar");

  std::string structures = "bvh,2l-bvh";
  int repeats = 5;
  auto* bench = app.add_subcommand("bench", "MRays/s of each structure beside Embree 3 on the same rays");
  ls_flags.add_to(bench);
  bench->add_option("--scene", scene_spec)->capture_default_str();
  bench->add_option("--rays", rays_path, "ray file (default: diffuse rays made here)");
  std::string bench_kind = "diffuse";
  bench->add_option("--kind", bench_kind, "rays to make when --rays is not given: diffuse, primary, random, or shadow (any hit)")
      ->capture_default_str()->check(CLI::IsMember({"diffuse", "primary", "random", "shadow"}));
  bool bench_any_hit = false;
  bench->add_flag("--any-hit", bench_any_hit, "occlusion queries (implied by --kind shadow)");
  bench->add_option("--count", count, "rays to make when --rays is not given")->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 28));
  bench->add_option("--seed", seed)->capture_default_str();
  bench->add_option("--structures", structures, "comma-separated structures")->capture_default_str();
  bench->add_option("--repeat", repeats, "timed runs per structure (median reported)")->capture_default_str()->check(CLI::Range(1, 100));
  bench->add_flag("--json", json, "machine-readable output");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "linespace-cpu: " << e.what() << " (see --help)\n";
    return 2;
  }

  ls_flags.progress = isatty(2) && !quiet;
  try {
    const Scene scene = load_scene(scene_spec);
    if (*build) {
      print_build(build_accel(scene, parse_structure(structure), ls_flags.options()), json);
    } else if (*trace) {
      const Accel accel = build_accel(scene, parse_structure(structure), ls_flags.options());
      const std::vector<lsk::Ray> in = read_rays(rays_path);
      std::vector<lsk::Hit> out(in.size());
      lsk::LsCounters counters{};
      trace_rays(accel, in.data(), out.data(), in.size(), any_hit, &counters);
      if (accel.spec.line_space()) print_counters(counters);
      write_hits(hits_path, out);
      size_t found = 0;
      for (const lsk::Hit& h : out) found += h.triangle != lsk::LS_INVALID;
      std::fprintf(stderr, "traced %zu rays with %s: %zu hits; wrote %s\n", in.size(), accel.spec.name().c_str(), found,
                   hits_path.c_str());
    } else if (*rays) {
      const RayKind k = parse_ray_kind(kind);
      const Accel exact = build_accel(scene, parse_structure("bvh"));
      write_rays(out_path, generate_rays(scene, exact, k, count, seed));
      std::fprintf(stderr, "wrote %zu %s rays to %s\n", count, kind.c_str(), out_path.c_str());
    } else if (*render_cmd) {
      RenderOptions options;
      options.schedule = parse_schedule(schedule);
      const Size size = parse_size(size_text);
      options.width = size.width;
      options.height = size.height;
      options.spp = spp;
      options.bounces = bounces;
      options.seed = seed;
      check_render_budget(options.width, options.height, bounces, ls_flags.options().ls.max_memory);
      std::map<std::string, Accel> built = build_schedule_structures(scene, options.schedule, ls_flags.options());
      const bool show = !quiet && isatty(2);
      Progress progress = [&](int done, int total) {
        if (!show) return;
        const int width = 30, filled = done * width / total;
        std::fprintf(stderr, "\rrender [%s%s] %d/%d samples", std::string(size_t(filled), '#').c_str(),
                     std::string(size_t(width - filled), ' ').c_str(), done, total);
        if (done == total) std::fprintf(stderr, "\n");
      };
      const RenderResult result = ls::render(scene, built, options, progress);
      RenderReportContext ctx{scene_spec, options.schedule.name(), spp, seed, &built};
      write_render_outputs(out_dir, result, ctx);
      std::printf("wrote %s/{total.exr, bounce_0..%d.exr, image.png, report.json}\n", out_dir.c_str(), bounces);
      std::printf("%s, %ux%u, %d spp, %d bounces, schedule %s: %.2f s; indirect %.2f MRays/s (%llu rays in %.3f s)\n",
                  scene_spec.c_str(), options.width, options.height, spp, bounces, options.schedule.name().c_str(),
                  result.seconds, result.indirect_mrays_per_s(), (unsigned long long)result.indirect_rays(),
                  result.indirect_seconds());
      if (result.dropped_samples)
        std::printf("warning: %llu non-finite contributions were left out\n", (unsigned long long)result.dropped_samples);
    } else if (*bench) {
      const std::vector<StructureSpec> specs = parse_structure_list(structures);
      std::vector<lsk::Ray> bench_rays;
      if (!rays_path.empty()) {
        bench_rays = read_rays(rays_path);
      } else {
        const Accel exact = build_accel(scene, parse_structure("bvh"));
        bench_rays = generate_rays(scene, exact, parse_ray_kind(bench_kind), count, seed);
      }
      if (bench_rays.empty()) throw InputError("bench: the ray file holds no rays");
      const bool occlusion = bench_any_hit || (rays_path.empty() && bench_kind == "shadow");
      print_bench(run_bench(scene, bench_rays, specs, repeats, ls_flags.options(), occlusion), json);
    }
  } catch (const Interrupted& e) {
    std::cerr << "\nlinespace-cpu: " << e.what() << ", stopped (no partially written output file is left)\n";
    return 128 + interrupt_signal();
  } catch (const InputError& e) {
    std::cerr << "linespace-cpu: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "linespace-cpu: error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
