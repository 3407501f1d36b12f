// Command-line pieces shared by linespace-cpu, linespace-gpu and linespace-validate: the image size
// and the Line Space flags, so every program spells and checks them the same way.
#pragma once

#include "common/base/progress.h"
#include "common/model/scene.h"
#include "common/structure/accel.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include <string>
#include <utility>
#include <vector>

namespace ls {

// A finite number in [lo, hi].  CLI::Range lets NaN through: every comparison with it is false
// (--ls-angle nan accepted every lookup, --max-memory nan skipped the budget).
inline CLI::Validator finite_range(double lo, double hi) {
  const std::string range = "[" + CLI::detail::to_string(lo) + " - " + CLI::detail::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size()) return "'" + text + "' is not a number";
        if (!(v >= lo && v <= hi)) return "Value " + text + " not in range " + range + " (a finite number)";
        return {};
      },
      "FLOAT in " + range);
}

// After parsing: a flag given an empty value (`--shard "$UNSET"`) is refused.  CLI11 stores the "",
// which the programs read as the flag not given: `render --shard ''` rendered the whole image.
inline void refuse_empty_values(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) refuse_empty_values(*sub);  // the ones given
  for (const CLI::Option* o : app.get_options())
    if (o->count() > 0 && o->get_type_size() != 0)
      for (const std::string& value : o->results())
        if (value.empty()) throw CLI::ValidationError(o->get_name(), "an empty value (an unset variable?)");
}

struct Size {
  uint32_t width = 512, height = 512;
};

inline Size parse_size(const std::string& text) {
  const size_t x = text.find('x');
  Size s;
  try {
    size_t used_w = 0, used_h = 0;
    if (x == std::string::npos) throw std::invalid_argument("x");
    const long w = std::stol(text.substr(0, x), &used_w);
    const long h = std::stol(text.substr(x + 1), &used_h);
    if (used_w != x || used_h != text.size() - x - 1) throw std::invalid_argument("trailing");
    if (w < 1 || h < 1 || w > 16384 || h > 16384) throw InputError("--size " + text + ": width and height must be in [1, 16384]");
    s.width = uint32_t(w);
    s.height = uint32_t(h);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception&) {
    throw InputError("--size '" + text + "' is not WIDTHxHEIGHT (e.g. 512x512)");
  }
  return s;
}

// --threads: the CPU threads a run may use (thread_limit.h), on every subcommand that does CPU work.
struct ThreadsFlag {
  int threads = 0;  // 0: all the process's CPUs
  void add_to(CLI::App* app) {
    app->add_option("--threads", threads, "CPU threads for builds, traces and Embree (0: all the process's CPUs)")
        ->capture_default_str();
  }
};

// Line Space options shared by every subcommand that builds a structure.
struct LsFlags {
  double angle = LsLookup{}.angle_degrees;
  int further_rays = LsBuildOptions{}.further_rays;
  uint32_t min_triangles = LsBuildOptions{}.min_triangles;
  std::string candidates = "compact";
  std::string behind = ls_behind_name(LsLookup{}.behind);
  std::string leave_reach = [] {  // LsLookup{}.leave_reach as text: parse_ls_leave_reach also takes "inf"
    char text[32];
    std::snprintf(text, sizeof text, "%g", double(LsLookup{}.leave_reach));
    return std::string(text);
  }();
  double max_memory_mb = 0.0;
  double ls_budget_mb = 0.0;
  size_t ls_budget_rays = LsPlanOptions{}.rays;
  bool progress = false;  // a Line Space progress bar on stderr (set when stderr is a terminal)
  std::string traversal = traversal_name(AccelOptions{}.traversal);
  int exact_width = AccelOptions{}.exact_width;
  std::string refused_value;
  std::vector<std::pair<std::string, const CLI::Option*>> refused_flags;  // a program without the fast path: its flags, refused when given

  // fast_path_flags: the CPU fast path's flags; a program without that path (linespace-gpu) leaves
  // them out, so that giving one is an error rather than silently ignored.
  void add_to(CLI::App* app, bool fast_path_flags = true) {
    if (fast_path_flags) {
      app->add_option("--traversal", traversal, "fast (wide SIMD BVH) or reference (the scalar kernels, the GPU's twin)")
          ->capture_default_str()->check(CLI::IsMember(traversal_names()));
      app->add_option("--exact-width", exact_width, "node width of the fast path's order-free walk: 4 or 8")
          ->capture_default_str()->check(CLI::IsMember({4, 8}));
    } else {  // parsed, then refused by options()
      for (const char* flag : {"--traversal", "--exact-width"})
        refused_flags.emplace_back(flag, app->add_option(flag, refused_value)->group(""));  // group "": not in --help
    }
    app->add_option("--ls-angle", angle, "refusal angle in degrees between ray and extrapolated normal (0: refuse all)")
        ->capture_default_str()->check(finite_range(0.0, 90.0));
    app->add_option("--ls-behind", behind,
                    "a plane hit behind the origin: exact (traverse the subtree), empty (the reverse shaft may answer "
                    "\"nothing ahead\", else traverse) or reverse (the reverse shaft's candidate answers)")
        ->capture_default_str()->check(CLI::IsMember(ls_behind_names()));
    app->add_option("--ls-leave-reach", leave_reach,
                    "with --ls-behind empty: how far outside its triangle, in patches, the reverse candidate's plane hit "
                    "may lie and still be the surface the ray leaves (inf: anywhere in its plane)")
        ->capture_default_str()
        ->check([](const std::string& text) {
          try {
            parse_ls_leave_reach(text);
            return std::string();
          } catch (const InputError& e) {  // CLI11 names the flag itself: from the quoted value on
            const std::string what = e.what();
            return what.substr(what.find('\''));
          }
        });
    app->add_option("--ls-further-rays", further_rays, "candidate search rays after the midpoint ray")
        ->capture_default_str()->check(CLI::Range(0, 1024));
    app->add_option("--ls-min-triangles", min_triangles, "subtrees with fewer triangles get no Line Space (0: paper)")
        ->capture_default_str();
    app->add_option("--ls-candidates", candidates, "compact (1/2/4-byte local index) or paper (4 bytes)")
        ->capture_default_str()->check(CLI::IsMember({"compact", "paper"}));
    app->add_option("--max-memory", max_memory_mb, "refuse a structure or render estimated above this many MB (0: half of RAM)")
        ->check(finite_range(0.0, 1e9));
    app->add_option("--ls-budget", ls_budget_mb, "2l-ls:auto: MB of Line Space (bytes_ls) to spend, D and N chosen per object")
        ->check(finite_range(0.0, 1e9));
    app->add_option("--ls-budget-rays", ls_budget_rays, "2l-ls:auto: pilot diffuse rays that measure each object's error")
        ->capture_default_str()->check(CLI::Range(size_t(1), size_t(1) << 24));
  }
  // --ls-angle and --ls-behind: what every lookup of a trace or render reads (no build does).
  LsLookup lookup() const {
    LsLookup l;
    l.angle_degrees = float(angle);
    l.behind = parse_ls_behind(behind);
    l.leave_reach = parse_ls_leave_reach(leave_reach);
    return l;
  }
  AccelOptions options() const {
    for (const auto& [name, flag] : refused_flags)
      if (flag->count() > 0)
        throw InputError(name + " is a flag of linespace-cpu's fast path; this command traces with the shared kernels");
    AccelOptions o;
    o.ls.further_rays = further_rays;
    o.ls.min_triangles = min_triangles;
    o.ls.paper_candidates = candidates == "paper";
    o.limits.max_memory = size_t(max_memory_mb * 1e6);
    // Under a byte is a budget below the fixed part, not "no budget".
    o.plan.budget = ls_budget_mb > 0.0 ? std::max<size_t>(1, size_t(ls_budget_mb * 1e6)) : 0;
    o.plan.rays = ls_budget_rays;
    o.plan.lookup = lookup();  // 2l-ls:auto measures its plan with the lookup the renders use
    o.traversal = parse_traversal(traversal);
    o.exact_width = exact_width;
    if (progress) {
      const ProgressLine line("line space", "LS nodes");
      o.ls.progress = [line](size_t done, size_t total) { line.update(done, total); };
    }
    return o;
  }
};

}  // namespace ls
