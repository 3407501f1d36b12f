#include "cli_report.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace ls {

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
                     {"ls_shafts_per_second", a.ls_info.seconds > 0.0 ? double(a.ls_info.ls_nodes * a.ls_info.shafts_per_ls) / a.ls_info.seconds : 0.0},
                     {"bytes_wide", a.bytes_wide()},
                     {"wide_build_seconds", a.wide_build_seconds},
                     {"build_seconds", a.build_seconds}};
    if (!device.empty()) j["device"] = device;
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
}

void print_counters(const lsk::LsCounters& c) {
  std::fprintf(stderr,
               "line space: %u lookups, %u empty shafts, %u accepted, refused %u (angle %u, behind the origin %u, "
               "beyond the current t %u, parallel %u, no shaft %u)\n",
               c.lookups, c.empty, c.accepted,
               c.refused_angle + c.refused_behind + c.refused_beyond + c.refused_parallel + c.refused_no_shaft,
               c.refused_angle, c.refused_behind, c.refused_beyond, c.refused_parallel, c.refused_no_shaft);
}


}  // namespace ls
