// Command-line pieces shared by linespace-cpu and linespace-gpu (DESIGN §9: both programs take the
// same subcommands and flags): --size parsing, the Line Space flags, and the build/counter reports.
// Include only from a program's main.cpp: LsFlags needs CLI11, which is slow to compile.
#pragma once

#include "accel.h"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace ls {

struct Size {
  uint32_t width = 512, height = 512;
};

// "WIDTHxHEIGHT", each in [1, 16384]; throws InputError.
Size parse_size(const std::string& text);

// Prints what `build` reports (DESIGN §9 keys); `device`, when given, names who built the candidates.
void print_build(const Accel& a, bool json, const std::string& device = "");

// Line Space lookup counters, one line on stderr.
void print_counters(const lsk::LsCounters& c);

// Line Space options shared by every subcommand that builds a structure.
struct LsFlags {
  double angle = LsOptions{}.angle_degrees;
  int further_rays = LsOptions{}.further_rays;
  uint32_t min_triangles = LsOptions{}.min_triangles;
  std::string candidates = "compact";
  double max_memory_mb = 0.0;

  void add_to(CLI::App* app) {
    app->add_option("--ls-angle", angle, "refusal angle in degrees between ray and extrapolated normal (0: refuse all)")
        ->capture_default_str()->check(CLI::Range(0.0, 90.0));
    app->add_option("--ls-further-rays", further_rays, "candidate search rays after the midpoint ray")
        ->capture_default_str()->check(CLI::Range(0, 1024));
    app->add_option("--ls-min-triangles", min_triangles, "subtrees with fewer triangles get no Line Space (0: paper)")
        ->capture_default_str();
    app->add_option("--ls-candidates", candidates, "compact (1/2/4-byte local index) or paper (4 bytes)")
        ->capture_default_str()->check(CLI::IsMember({"compact", "paper"}));
    app->add_option("--max-memory", max_memory_mb, "refuse a Line Space estimated above this many MB (0: half of RAM)")
        ->check(CLI::Range(0.0, 1e9));
  }
  AccelOptions options() const {
    AccelOptions o;
    o.ls.angle_degrees = float(angle);
    o.ls.further_rays = further_rays;
    o.ls.min_triangles = min_triangles;
    o.ls.paper_candidates = candidates == "paper";
    o.ls.max_memory = size_t(max_memory_mb * 1e6);
    return o;
  }
};

}  // namespace ls
