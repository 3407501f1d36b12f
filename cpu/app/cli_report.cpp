#include "cpu/app/cli_report.h"

#include "common/structure/accel.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace ls {

nlohmann::json ls_plan_json(const LsPlan& p) {
  auto dn = [](const ObjectLs& o) { return o.n > 0 ? std::to_string(o.depth) + ":" + std::to_string(o.n) : std::string("none"); };
  auto figures = [](const PilotFigures& f) {
    return nlohmann::json{{"bytes_ls", f.bytes_ls}, {"pilot_error", f.error}, {"pilot_saved_work", f.saved_work}};
  };
  nlohmann::json rows = nlohmann::json::array();
  for (const LsPlanRow& r : p.rows)
    rows.push_back({{"mesh", r.mesh},
                    {"name", r.name},
                    {"triangles", r.triangles},
                    {"instances", r.instances},
                    {"pilot_hits", r.hits},
                    {"pilot_rays_crossing", r.relevant},
                    {"chosen", dn(r.chosen)},
                    {"reference", dn(r.reference)},
                    {"bytes", r.bytes},
                    {"pilot_error", r.error},
                    {"pilot_saved_work", r.saved_work},
                    {"reason", r.reason}});
  return {{"budget_bytes", p.budget},
          {"fixed_bytes", p.fixed_bytes},
          {"predicted_bytes", p.predicted_bytes},
          // null where no uniform structure fits the budget (there is no reference to compare with)
          {"reference", p.reference.empty() ? nlohmann::json() : nlohmann::json(p.reference)},
          {"reference_chosen", p.reference_chosen},
          {"lambda", p.lambda},
          {"plan", figures(p.plan)},
          {"uniform", p.reference.empty() ? nlohmann::json() : figures(p.uniform)},
          {"pilot_rays", p.pilot_rays},
          {"pilot_shadow_rays", p.pilot_shadow_rays},
          {"evaluations", p.evaluations},
          {"shafts_searched", p.shafts_searched},
          {"seconds", p.seconds},
          {"objects", rows}};
}

void print_ls_plan(const LsPlan& p) {
  std::printf("ls_plan        budget %.2f MB: %.2f MB (fixed %.2f MB); %zu + %zu shadow pilot rays, %zu evaluations, %zu shafts "
              "searched, %.2f s\n",
              double(p.budget) / 1e6, double(p.predicted_bytes) / 1e6, double(p.fixed_bytes) / 1e6, p.pilot_rays,
              p.pilot_shadow_rays, p.evaluations, p.shafts_searched, p.seconds);
  std::printf("  on the pilot  plan: error %.5f, saved work %.1f per ray, %.2f MB", p.plan.error, p.plan.saved_work,
              double(p.plan.bytes_ls) / 1e6);
  if (!p.reference.empty())
    std::printf("; reference %s: error %.5f, saved work %.1f per ray, %.2f MB%s", p.reference.c_str(), p.uniform.error,
                p.uniform.saved_work, double(p.uniform.bytes_ls) / 1e6, p.reference_chosen ? " (the plan is the reference)" : "");
  else
    std::printf("; no uniform structure of the menu fits the budget");
  std::printf("\n  %-5s %-24s %10s %5s %7s %6s %6s %9s %9s %8s  %s\n", "mesh", "name", "triangles", "inst", "hits", "D:N", "ref",
              "MB", "error", "saved", "why");
  for (const LsPlanRow& r : p.rows) {
    auto dn = [](const ObjectLs& o) { return o.n > 0 ? std::to_string(o.depth) + ":" + std::to_string(o.n) : std::string("-"); };
    std::printf("  %-5u %-24.24s %10zu %5zu %7zu %6s %6s %9.3f %9.5f %8.2f  %s\n", r.mesh, r.name.c_str(), r.triangles,
                r.instances, r.hits, dn(r.chosen).c_str(), dn(r.reference).c_str(), double(r.bytes) / 1e6, r.error,
                r.saved_work, r.reason.c_str());
  }
}

void print_build(const Accel& a, bool json, const std::string& device) {
  if (json) {
    nlohmann::json j{{"structure", a.spec.name()},
                     {"triangles", a.world_triangles},
                     {"objects", a.objects},
                     {"instances", a.instance_count},
                     {"nodes", a.nodes.size() + a.top_nodes.size()},
                     {"max_depth", a.max_depth},
                     {"ls_nodes", a.ls_info.ls_nodes},
                     {"shafts_per_ls", a.ls_info.shafts_per_ls},
                     {"empty_shafts", a.ls_info.empty_shafts},
                     {"bytes_total", a.bytes_total()},
                     {"bytes_ls", a.bytes_ls()},
                     {"bytes_ls_candidates", a.ls_info.candidate_bytes},
                     {"bytes_ls_candidates_paper", a.ls_info.candidate_bytes_paper},
                     {"bytes_ls_candidates_compact", a.ls_info.candidate_bytes_compact},
                     {"ls_build_seconds", a.ls_info.seconds},
                     {"ls_shafts_per_second", a.ls_info.seconds > 0.0 ? double(a.ls_info.shafts) / a.ls_info.seconds : 0.0},
                     {"bytes_wide", a.bytes_wide()},
                     {"wide_build_seconds", a.wide_build_seconds},
                     {"build_seconds", a.build_seconds}};
    if (!device.empty()) j["device"] = device;
    if (a.ls_plan) j["ls_plan"] = ls_plan_json(*a.ls_plan);
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("structure      %s\ntriangles      %zu\nobjects        %zu\ninstances      %zu\nnodes          %zu\n"
              "max_depth      %d\nls_nodes       %zu\nshafts_per_ls  %zu\nempty_shafts   %zu\n"
              "bytes_total    %zu (%.2f MB)\nbytes_ls       %zu (%.2f MB; candidates %.2f MB, paper mode %.2f MB)\n"
              "build_seconds  %.3f (Line Space %.3f)\n",
              a.spec.name().c_str(), a.world_triangles, a.objects, a.instance_count, a.nodes.size() + a.top_nodes.size(),
              a.max_depth, a.ls_info.ls_nodes, a.ls_info.shafts_per_ls, a.ls_info.empty_shafts, a.bytes_total(),
              double(a.bytes_total()) / 1e6, a.bytes_ls(), double(a.bytes_ls()) / 1e6, double(a.ls_info.candidate_bytes) / 1e6,
              double(a.ls_info.candidate_bytes_paper) / 1e6, a.build_seconds, a.ls_info.seconds);
  if (!device.empty()) std::printf("device         %s\n", device.c_str());
  if (a.ls_plan) print_ls_plan(*a.ls_plan);
}

void print_counters(const lsk::LsCounters& c) {
  std::fprintf(stderr,
               "line space: %u lookups, %u empty shafts, %u accepted, refused %u (angle %u, before the window %u, "
               "past the window %u, parallel %u, no shaft %u)\n",
               c.lookups, c.empty, c.accepted,
               c.refused_angle + c.refused_behind + c.refused_beyond + c.refused_parallel + c.refused_no_shaft,
               c.refused_angle, c.refused_behind, c.refused_beyond, c.refused_parallel, c.refused_no_shaft);
}

void print_other_hits(const std::vector<lsk::Hit>& hits, const std::vector<lsk::Hit>& against, const std::string& against_path) {
  size_t other = 0, missed = 0, extra = 0;
  for (size_t i = 0; i < hits.size(); ++i) {
    const bool hit = hits[i].triangle != lsk::LS_INVALID, hit_there = against[i].triangle != lsk::LS_INVALID;
    other += hits[i].instance != against[i].instance || hits[i].triangle != against[i].triangle;
    missed += hit_there && !hit;
    extra += hit && !hit_there;
  }
  std::fprintf(stderr, "against %s: %zu of %zu rays (%.2f %%) hit another triangle (%zu miss where it hits, %zu hit where it misses)\n",
               against_path.c_str(), other, hits.size(), hits.empty() ? 0.0 : 100.0 * double(other) / double(hits.size()), missed,
               extra);
}

}  // namespace ls
