// linespace-validate: measures what the Line Space's approximation costs in image error and buys in
// speed and memory (docs/design.md §7, §9).
// Exit status: 0 success, 1 a check failed, 2 bad input or usage (one-line reason on stderr).
#include "common/base/memory_budget.h"
#include "common/base/progress.h"
#include "common/base/ray_files.h"
#include "common/base/thread_limit.h"
#include "common/structure/accel.h"
#include "cpu/app/cli_flags.h"
#include "cpu/build/build_accel.h"
#include "cpu/trace/ray_generators.h"
#include "cpu/trace/trace_rays.h"
#include "scenes/load_scene.h"
#include "validate/bound_study.h"
#include "validate/budget_study.h"
#include "validate/cross_check.h"
#include "validate/paper_tables.h"
#include "validate/policy_study.h"
#include "validate/rmse_study.h"
#include "validate/sweep.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <iostream>

namespace {

using namespace ls;

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Image settings shared by every study.
struct ImageFlags {
  std::string size = "256x256", spp = "4";
  int bounces = 3;
  uint32_t seed = 1;
  int timing_rounds = ImageSettings{}.timing_rounds;
  // Empty: not given (one ImageFlags serves every subcommand, so the flags' own counts cannot tell).
  std::string auto_rel_stderr, auto_seconds;

  void add_to(CLI::App* app) {
    app->add_option("--size", size, "WIDTHxHEIGHT")->capture_default_str();
    app->add_option("--spp", spp, "samples per pixel (1..65536), or auto: from " + std::to_string(kAutoStartSpp) +
                                      ", doubled per configuration until rmse_bias is known to --auto-rel-stderr")
        ->capture_default_str();
    app->add_option("--auto-rel-stderr", auto_rel_stderr,
                    "--spp auto: stop once rmse_bias's standard error is at most this fraction of it (default " +
                        number_text(SppAuto{}.rel_stderr) + ")");
    app->add_option("--auto-seconds", auto_seconds,
                    "--spp auto: stop before a doubling that would end past this many seconds of a configuration "
                    "(default " + number_text(SppAuto{}.seconds) + ")");
    app->add_option("--bounces", bounces, "indirect bounces after the primary hit")->capture_default_str()->check(CLI::Range(1, 64));
    app->add_option("--seed", seed)->capture_default_str();
    app->add_option("--timing-rounds", timing_rounds,
                    "renders of each configuration and of the exact F-BVH right after it; the speed-up is the median "
                    "ratio")
        ->capture_default_str()->check(CLI::Range(1, 100));
  }
  static constexpr int kAutoStartSpp = 4;
  // The whole text as a number, else NaN (which every range check refuses).
  static double number(const std::string& text) {
    size_t used = 0;
    double v = NAN;
    try {
      v = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    return used == text.size() && used > 0 ? v : NAN;
  }
  ImageSettings settings() const {
    const Size s = parse_size(size);
    ImageSettings i;
    i.width = s.width;
    i.height = s.height;
    i.bounces = bounces;
    i.seed = seed;
    i.timing_rounds = timing_rounds;
    if (spp == "auto") {
      const double rel = auto_rel_stderr.empty() ? SppAuto{}.rel_stderr : number(auto_rel_stderr);
      const double seconds = auto_seconds.empty() ? SppAuto{}.seconds : number(auto_seconds);
      if (!(rel > 0.0 && rel < 1.0))
        throw InputError("--auto-rel-stderr " + auto_rel_stderr + ": expected a fraction in (0, 1)");
      if (!(seconds > 0.0 && seconds <= 1e7))
        throw InputError("--auto-seconds " + auto_seconds + ": expected seconds in (0, 1e7]");
      i.spp = kAutoStartSpp;
      i.auto_spp.enabled = true;
      i.auto_spp.rel_stderr = rel;
      i.auto_spp.seconds = seconds;
    } else {
      size_t used = 0;
      long v = 0;
      try {
        v = std::stol(spp, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != spp.size() || v < 1 || v > (1 << 16))
        throw InputError("--spp " + spp + ": expected an integer in [1, 65536] or auto");
      if (!auto_rel_stderr.empty() || !auto_seconds.empty())
        throw InputError("--auto-rel-stderr and --auto-seconds need --spp auto");
      i.spp = int(v);
    }
    return i;
  }
};

void log_line(const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); }

// The plot is a separate step so it can be replaced: Debian's python3 with matplotlib.
void plot_sweep(const std::string& dir) {
  const std::string cmd = "/usr/bin/python3 '" LINESPACE_PLOT_SCRIPT "' '" + dir + "'";
  const int status = std::system(cmd.c_str());
  if (status != 0)
    throw InputError("the plot step failed (" + cmd + ": its reason is above; it needs Debian's python3-matplotlib, which "
                     "scripts/setup.sh installs). The data is in " + dir + "/sweep.{csv,json}");
}

std::set<int> int_set(const std::string& text, const std::string& flag, int lo, int hi) {
  const std::vector<int> v = parse_int_list(text, flag, lo, hi);
  return {v.begin(), v.end()};
}

std::vector<std::string> scene_list(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (item.empty()) throw InputError("--scenes '" + text + "': empty scene name");
    out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return without_repeats(out);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"linespace-validate: image error, speed and memory of the Line Space, measured"};
  app.require_subcommand(1);
  std::string scene_spec = "builtin:cornell", device = "cpu", out_dir;
  LsFlags ls_flags;
  ThreadsFlag threads_flag;
  ImageFlags image_flags;

  std::string structures = "f-ls:8:6,2l-ls:4:6";
  float heatmap_max = 0.1f;
  auto* rmse_cmd = app.add_subcommand("rmse", "RMSE per start bounce against the all-exact render (the paper's Table 3)");
  rmse_cmd->add_option("--scene", scene_spec, "scene file or builtin:NAME")->capture_default_str();
  rmse_cmd->add_option("--structures", structures, "comma-separated structures")->capture_default_str();
  rmse_cmd->add_option("--device", device, "cpu, gpu or gpu:NAME|INDEX (a Vulkan device)")->capture_default_str();
  rmse_cmd->add_option("--out", out_dir, "folder for rmse.{md,csv,json}, heat-maps and images")->default_val("out/rmse");
  rmse_cmd->add_option("--heatmap-max", heatmap_max, "per-pixel error at the top of the heat-map's ramp")
      ->capture_default_str()->check(finite_range(1e-6, 1.0));
  image_flags.add_to(rmse_cmd);
  ls_flags.add_to(rmse_cmd);
  threads_flag.add_to(rmse_cmd);

  std::string families = "f-ls,2l-ls", depths = "0,2,4,6,8", subdivisions = "4,6,8";
  std::string angles = number_text(LsLookup{}.angle_degrees);  // the lookup's default angle
  std::string behinds = ls_behind_name(LsLookup{}.behind);
  std::string min_triangles = std::to_string(LsBuildOptions{}.min_triangles);
  int start_bounce = 1;
  bool no_plot = false;
  auto* sweep_cmd = app.add_subcommand(
      "sweep", "MRays/s against RMSE over D, N, the refusal angle, the behind mode and the smallest subtree; plots the trade-off");
  sweep_cmd->add_option("--scene", scene_spec, "scene file or builtin:NAME")->capture_default_str();
  sweep_cmd->add_option("--families", families, "f-ls, 2l-ls or both")->capture_default_str();
  sweep_cmd->add_option("--depths", depths, "integration depths D")->capture_default_str();
  sweep_cmd->add_option("--subdivisions", subdivisions, "subdivisions N")->capture_default_str();
  sweep_cmd->add_option("--angles", angles, "refusal angles in degrees (default: --ls-angle's)")->capture_default_str();
  sweep_cmd->add_option("--behinds", behinds, "--ls-behind modes: exact, empty, reverse (default: --ls-behind's)")
      ->capture_default_str();
  sweep_cmd->add_option("--min-triangles", min_triangles,
                        "smallest subtrees that get a Line Space, each value a build (default: --ls-min-triangles')")
      ->capture_default_str();
  sweep_cmd->add_option("--start-bounce", start_bounce, "the Line Space traces bounces >= this one")->capture_default_str();
  sweep_cmd->add_option("--device", device, "cpu, gpu or gpu:NAME|INDEX (a Vulkan device)")->capture_default_str();
  sweep_cmd->add_option("--out", out_dir, "folder for sweep.{csv,json,md} and tradeoff.{png,svg}")->default_val("out/sweep");
  sweep_cmd->add_flag("--no-plot", no_plot, "write the data only");
  image_flags.add_to(sweep_cmd);
  ls_flags.add_to(sweep_cmd);
  threads_flag.add_to(sweep_cmd);

  std::string scenes = "builtin:cornell", tables = "2,3,4", paper_n = "6,10";
  auto* paper_cmd = app.add_subcommand("paper", "the paper's Tables 2, 3 and 4 on our scenes, beside the paper's figures");
  paper_cmd->add_option("--scenes", scenes, "comma-separated scenes")->capture_default_str();
  paper_cmd->add_option("--tables", tables, "which of Tables 2, 3, 4")->capture_default_str();
  paper_cmd->add_option("--subdivisions", paper_n, "the paper's N to run: 6, 10 or both")->capture_default_str();
  paper_cmd->add_option("--device", device, "cpu, gpu or gpu:NAME|INDEX (a Vulkan device)")->capture_default_str();
  paper_cmd->add_option("--out", out_dir, "folder for paper.{md,json} and each scene's rmse files")->default_val("out/paper");
  paper_cmd->add_option("--heatmap-max", heatmap_max, "per-pixel error at the top of the heat-map's ramp")
      ->capture_default_str()->check(finite_range(1e-6, 1.0));
  image_flags.add_to(paper_cmd);
  ls_flags.add_to(paper_cmd);
  threads_flag.add_to(paper_cmd);

  std::string uniform = "2l-ls:0:10,2l-ls:4:6";
  auto* budget_cmd = app.add_subcommand("budget", "2l-ls:auto against uniform 2l-ls:D:N of the same memory: RMSE, MRays/s, the choice");
  budget_cmd->add_option("--scene", scene_spec, "scene file or builtin:NAME")->capture_default_str();
  budget_cmd->add_option("--uniform", uniform, "uniform 2l-ls:D:N structures; each one's bytes_ls is a budget")->capture_default_str();
  budget_cmd->add_option("--device", device, "cpu, gpu or gpu:NAME|INDEX (a Vulkan device)")->capture_default_str();
  budget_cmd->add_option("--out", out_dir, "folder for budget.{md,csv,json}")->default_val("out/budget");
  image_flags.add_to(budget_cmd);
  ls_flags.add_to(budget_cmd);
  threads_flag.add_to(budget_cmd);
  std::string policy_structure = "f-ls:8:6", thresholds = "0.05,0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.99", start_bounces;
  int policy_repeats = 3;  // as --timing-rounds: single renders on a shared host move by more than a Line Space's effect
  auto* policy_cmd = app.add_subcommand("policy", "bounce policy against throughput policy (render --throughput-switch) at equal speed");
  policy_cmd->add_option("--scene", scene_spec, "scene file or builtin:NAME")->capture_default_str();
  policy_cmd->add_option("--structure", policy_structure, "the approximate structure X both policies switch to")->capture_default_str();
  policy_cmd->add_option("--thresholds", thresholds, "throughput policy: X below these throughput luminances")->capture_default_str();
  policy_cmd->add_option("--start-bounces", start_bounces, "bounce policy: X from these bounces on (default 1..--bounces)");
  policy_cmd->add_option("--repeat", policy_repeats, "timed renders per configuration, round-robin (median MRays/s)")
      ->capture_default_str()->check(CLI::Range(1, 100));
  policy_cmd->add_option("--device", device, "cpu, gpu or gpu:NAME|INDEX (a Vulkan device)")->capture_default_str();
  policy_cmd->add_option("--out", out_dir, "folder for policy.{md,csv,json}")->default_val("out/policy");
  image_flags.add_to(policy_cmd);
  ls_flags.add_to(policy_cmd);
  threads_flag.add_to(policy_cmd);

  std::string bound_structures = "f-ls:8:6,2l-ls:4:6", bound_rays, bound_kind = "diffuse";
  size_t bound_count = 200000;
  uint32_t bound_seed = 1;
  auto* bound_cmd = app.add_subcommand("bound", "the traversal work a Line Space could save at most (an exact, free lookup) "
                                                "against what it saves, on the same rays (CPU reference kernels)");
  bound_cmd->add_option("--scene", scene_spec, "scene file or builtin:NAME")->capture_default_str();
  bound_cmd->add_option("--structures", bound_structures, "comma-separated Line Space structures")->capture_default_str();
  bound_cmd->add_option("--rays", bound_rays, "ray file (default: --count rays of --kind made here)");
  bound_cmd->add_option("--kind", bound_kind, "rays to make: diffuse, primary or random")
      ->capture_default_str()->check(CLI::IsMember({"diffuse", "primary", "random"}));
  bound_cmd->add_option("--count", bound_count, "rays to make")->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 26));
  bound_cmd->add_option("--seed", bound_seed)->capture_default_str();
  bound_cmd->add_option("--out", out_dir, "folder for bound.{md,csv,json}")->default_val("out/bound");
  ls_flags.add_to(bound_cmd, false);  // always the reference kernels: they count their work
  threads_flag.add_to(bound_cmd);

  // CPU-versus-GPU cross-checks: exit 1 on any difference.
  validate::CrossCheckCommand check;
  std::vector<float> check_offset;
  auto add_check_flags = [&](CLI::App* cmd) {
    cmd->add_option("--scene", check.scene, "scene file or builtin:NAME")->capture_default_str();
    cmd->add_option("--structure", check.structure, "bvh, 2l-bvh, f-ls:D:N or 2l-ls:D:N")->capture_default_str();
    cmd->add_option("--device", check.device, "Vulkan device: index or part of its name (default: discrete GPU first)");
    cmd->add_option("--scale", check.scale, "scale the scene first (numerical extremes)")->capture_default_str();
    cmd->add_option("--offset", check_offset, "then move it by X Y Z")->expected(3);
    ls_flags.add_to(cmd);
    threads_flag.add_to(cmd);
  };
  auto* candidates_cmd = app.add_subcommand("candidates", "Line Space candidates built on CPU and GPU, compared shaft by shaft");
  add_check_flags(candidates_cmd);
  auto* hits_cmd = app.add_subcommand("hits", "hits traced on CPU and GPU, compared (ids and the bits of t, u, v)");
  add_check_flags(hits_cmd);
  hits_cmd->add_option("--rays", check.rays, "ray file (default: --count rays of --kind made here)");
  hits_cmd->add_option("--kind", check.kind, "primary, diffuse or random")->capture_default_str();
  hits_cmd->add_option("--count", check.count)->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 26));
  hits_cmd->add_option("--seed", check.seed)->capture_default_str();
  hits_cmd->add_flag("--any-hit", check.any_hit, "stop at the first hit in [tmin, tmax]");

  try {
    app.parse(argc, argv);
    refuse_empty_values(app);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "linespace-validate: " << e.what() << " (see --help)\n";
    return 2;
  }

  ls_flags.progress = stderr_is_terminal();  // Line Space builds: a progress line on a terminal
  // The image settings of the studies, with the Line Space lookup of --ls-angle and --ls-behind.
  const auto image_settings = [&] {
    ImageSettings s = image_flags.settings();
    s.lookup = ls_flags.lookup();
    return s;
  };
  try {
    const ThreadLimit threads(threads_flag.threads);  // first: a bad count is refused before any work
    for (size_t i = 0; i < check_offset.size() && i < 3; ++i) check.offset[i] = check_offset[i];
    if (*candidates_cmd) return validate::run_candidates_command(check, ls_flags.options());
    if (*hits_cmd) return validate::run_hits_command(check, ls_flags.options(), ls_flags.lookup());
    // Before any work: a study that has run for hours must not fail at its end on its --out.
    std::error_code ec;
    if (!out_dir.empty() && std::filesystem::exists(out_dir, ec) && !std::filesystem::is_directory(out_dir, ec))
      throw InputError("--out '" + out_dir + "' is a file, not a folder");
    if (*rmse_cmd) {
      const std::vector<StructureSpec> specs = without_repeats(parse_structure_list(structures));
      const ImageSettings settings = image_settings();
      const Scene scene = load_scene(scene_spec);
      auto renderer = make_study_renderer(device, scene, ls_flags.options());
      const RmseStudy study = run_rmse_study(*renderer, scene_spec, specs, settings, out_dir, heatmap_max, log_line);
      write_rmse_study(out_dir, study);
      std::printf("%s, %ux%u, %s spp, %d bounces, %s\n\n%s\nwrote %s/{rmse.md, rmse.csv, rmse.json, *_heatmap.png, "
                  "*_side_by_side.png}\n",
                  scene_spec.c_str(), settings.width, settings.height, image_flags.spp.c_str(), settings.bounces,
                  study.device.c_str(), study.summary().markdown().c_str(), out_dir.c_str());
    } else if (*sweep_cmd) {
      SweepGrid grid;
      grid.families = parse_families(families);
      grid.depths = parse_int_list(depths, "--depths", 0, kMaxLsDepth);
      grid.subdivisions = parse_int_list(subdivisions, "--subdivisions", 1, kMaxLsSubdivision);
      // The angle is --angles' list or --ls-angle's one value (the default of both): never one silently over the other.
      const bool angles_given = sweep_cmd->get_option("--angles")->count() > 0;
      if (angles_given && sweep_cmd->get_option("--ls-angle")->count() > 0)
        throw InputError("sweep: --angles and --ls-angle both set the refusal angle; give one of them");
      const ImageSettings settings = image_settings();
      grid.angles = angles_given ? parse_angle_list(angles) : std::vector<float>{settings.lookup.angle_degrees};
      const bool behinds_given = sweep_cmd->get_option("--behinds")->count() > 0;
      if (behinds_given && sweep_cmd->get_option("--ls-behind")->count() > 0)
        throw InputError("sweep: --behinds and --ls-behind both set the behind mode; give one of them");
      grid.behinds = behinds_given ? parse_behind_list(behinds) : std::vector<LsBehind>{settings.lookup.behind};
      const bool min_triangles_given = sweep_cmd->get_option("--min-triangles")->count() > 0;
      if (min_triangles_given && sweep_cmd->get_option("--ls-min-triangles")->count() > 0)
        throw InputError("sweep: --min-triangles and --ls-min-triangles both set the smallest subtree; give one of them");
      grid.start_bounce = start_bounce;
      const Scene scene = load_scene(scene_spec);
      const AccelOptions accel_options = ls_flags.options();
      grid.min_triangles = min_triangles_given ? parse_min_triangles_list(min_triangles)
                                               : std::vector<uint32_t>{accel_options.ls.min_triangles};
      auto renderer = make_study_renderer(device, scene, accel_options);
      const Sweep sweep = run_sweep(*renderer, scene_spec, grid, settings, log_line);
      write_sweep(out_dir, sweep);
      std::printf("%s\nwrote %s/{sweep.csv, sweep.json, sweep.md}\n", sweep.table().markdown().c_str(), out_dir.c_str());
      // Nothing to plot, and nothing learnt: say why here (the plot step once took the blame).
      const auto measured = std::find_if(sweep.points.begin(), sweep.points.end(), [](const SweepPoint& p) { return p.refused.empty(); });
      if (measured == sweep.points.end() && !sweep.points.empty())
        throw InputError("sweep: every configuration was refused (" + sweep.points.front().structure + ": " +
                         sweep.points.front().refused + ")");
      if (!no_plot) {
        plot_sweep(out_dir);
        std::printf("wrote %s/{tradeoff.png, tradeoff.svg}\n", out_dir.c_str());
      }
    } else if (*budget_cmd) {
      const std::vector<StructureSpec> specs = parse_structure_list(uniform);
      const ImageSettings settings = image_settings();
      const Scene scene = load_scene(scene_spec);
      const AccelOptions accel_options = ls_flags.options();
      auto renderer = make_study_renderer(device, scene, accel_options);
      const BudgetStudy study = run_budget_study(*renderer, scene_spec, specs, settings, accel_options.plan, log_line);
      write_budget_study(out_dir, study);
      std::printf("%s, %ux%u, %s spp, %d bounces, %s\n\n%s\n%s\nwrote %s/{budget.md, budget.csv, budget.json}\n", scene_spec.c_str(),
                  settings.width, settings.height, image_flags.spp.c_str(), settings.bounces, study.device.c_str(),
                  study.table().markdown().c_str(), study.choices().markdown().c_str(), out_dir.c_str());
    } else if (*policy_cmd) {
      if (policy_cmd->get_option("--timing-rounds")->count() > 0)
        throw InputError("policy: --timing-rounds does not apply; policy times every configuration and the reference "
                         "round-robin, --repeat times");
      const StructureSpec spec = parse_structure(policy_structure);
      const ImageSettings settings = image_settings();
      std::vector<int> starts;
      if (start_bounces.empty())
        for (int k = 1; k <= settings.bounces; ++k) starts.push_back(k);
      else
        starts = parse_int_list(start_bounces, "--start-bounces", 1, settings.bounces);
      const std::vector<float> ts = parse_threshold_list(thresholds);
      const Scene scene = load_scene(scene_spec);
      auto renderer = make_study_renderer(device, scene, ls_flags.options());
      const PolicyStudy study = run_policy_study(*renderer, scene_spec, spec, starts, ts, settings, log_line, policy_repeats);
      write_policy_study(out_dir, study);
      std::printf("%s, %ux%u, %s spp, %d bounces, %s\n\n%s\nwrote %s/{policy.md, policy.csv, policy.json}\n", scene_spec.c_str(),
                  settings.width, settings.height, image_flags.spp.c_str(), settings.bounces, study.device.c_str(),
                  study.markdown().c_str(), out_dir.c_str());
    } else if (*bound_cmd) {
      const std::vector<StructureSpec> specs = parse_structure_list(bound_structures);
      AccelOptions accel_options = ls_flags.options();
      accel_options.fast_path = false;
      check_ray_budget("bound", bound_rays, bound_count, 1, accel_options.limits.max_memory);
      const Scene scene = load_scene(scene_spec);
      std::vector<lsk::Ray> rays;
      std::string rays_name = bound_rays;
      if (bound_rays.empty()) {
        rays = generate_rays(scene, build_accel(scene, parse_structure("bvh"), accel_options), parse_ray_kind(bound_kind),
                             bound_count, bound_seed);
        rays_name = bound_kind + ", " + std::to_string(bound_count) + ", seed " + std::to_string(bound_seed);
      } else {
        rays = read_rays(bound_rays);
      }
      const BoundStudy study = run_bound_study(scene, scene_spec, rays, rays_name, specs, accel_options, ls_flags.lookup(), log_line);
      write_bound_study(out_dir, study);
      std::printf("%s, %zu rays (%s); work a ray in box tests (+ %.1f a triangle test, %.1f a lookup), reference kernels\n\n%s\n"
                  "wrote %s/{bound.md, bound.csv, bound.json}\n",
                  scene_spec.c_str(), study.ray_count, rays_name.c_str(), kTriangleTestWork, kLookupWork,
                  study.table().markdown().c_str(), out_dir.c_str());
    } else if (*paper_cmd) {
      PaperOptions options;
      options.scenes = scene_list(scenes);
      options.tables = int_set(tables, "--tables", 2, 4);
      options.subdivisions = int_set(paper_n, "--subdivisions", 6, 10);
      options.settings = image_settings();
      options.device = device;
      options.heatmap_max = heatmap_max;
      const PaperReport report = run_paper(options, ls_flags.options(), out_dir, log_line);
      std::printf("%s\nwrote %s/{paper.md, paper.json}\n", report.markdown.c_str(), out_dir.c_str());
    }
  } catch (const InputError& e) {
    std::cerr << "linespace-validate: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "linespace-validate: error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
