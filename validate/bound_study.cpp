#include "validate/bound_study.h"

#include "common/model/scene.h"
#include "common/structure/accel.h"
#include "cpu/build/build_structures.h"
#include "cpu/trace/trace_rays.h"

#include <chrono>
#include <filesystem>

namespace ls {
namespace {

TraceWorkTotals traced_work(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays,
                            lsk::LsCounters& counters) {
  std::vector<lsk::Hit> hits(rays.size());
  TraceWorkTotals work;
  const std::vector<uint8_t> ls_subtrees = line_space_subtrees(accel);
  trace_rays(accel, lookup, rays.data(), hits.data(), rays.size(), false, &counters, Traversal::Reference, &work, &ls_subtrees);
  return work;
}

double per_ray(double value, size_t rays) { return rays ? value / double(rays) : 0.0; }

}  // namespace

double BoundRow::exact_work_units() const { return work_units(exact_work.box_tests, exact_work.triangle_tests, 0); }

double BoundRow::oracle_work_units() const {
  return work_units(exact_work.box_tests - exact_work.box_tests_in_ls, exact_work.triangle_tests - exact_work.triangle_tests_in_ls,
                    exact_work.lookups);
}

double BoundRow::traced_work_units() const {
  return work_units(traced_work.box_tests, traced_work.triangle_tests, traced_work.lookups);
}

double BoundRow::share_below_ls() const {
  const double exact = exact_work_units();
  return exact > 0.0 ? work_units(exact_work.box_tests_in_ls, exact_work.triangle_tests_in_ls, 0) / exact : 0.0;
}

BoundStudy run_bound_study(const Scene& scene, const std::string& scene_name, const std::vector<lsk::Ray>& rays,
                           const std::string& rays_name, const std::vector<StructureSpec>& specs, const AccelOptions& options,
                           const LsLookup& lookup, const std::function<void(const std::string&)>& log) {
  for (const StructureSpec& s : specs)
    if (!s.line_space())
      throw InputError("bound: --structures takes Line Space structures (f-ls:D:N, 2l-ls:D:N, 2l-ls:auto), not '" + s.name() +
                       "'; each is compared with its own BVH");
  if (rays.empty()) throw InputError("bound: no rays to trace");
  BoundStudy study;
  study.scene = scene_name;
  study.rays = rays_name;
  study.ray_count = rays.size();
  for (const StructureSpec& spec : specs) {
    const auto t0 = std::chrono::steady_clock::now();
    const Accel accel = build_planned_accel(scene, spec, options);
    BoundRow row;
    row.structure = spec.name();
    row.exact = spec.two_level() ? "2l-bvh" : "bvh";
    row.ls_nodes = accel.ls_info.ls_nodes;
    // A refusal angle of 0 refuses every lookup (ls_lookup.h): the walk is the BVH's own, node for node.
    LsLookup refuse_all = lookup;
    refuse_all.angle_degrees = 0.0f;
    lsk::LsCounters refused{};
    row.exact_work = traced_work(accel, refuse_all, rays, refused);
    row.traced_work = traced_work(accel, lookup, rays, row.traced);
    study.rows.push_back(row);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    log(row.structure + ": bound " + fixed(row.bound(), 2) + "x, achieved " + fixed(row.achieved(), 2) + "x its " + row.exact +
        "'s work (" + fixed(seconds, 1) + " s)");
  }
  return study;
}

Table BoundStudy::table() const {
  Table t;
  t.header = {"structure", "LS nodes", "exact work", "below LS nodes", "oracle work", "LS work", "lookups (oracle)",
              "lookups (LS)", "accepted", "bound", "achieved"};
  for (const BoundRow& r : rows) {
    const uint64_t lookups = r.traced.lookups;
    t.rows.push_back({r.structure + " vs " + r.exact, std::to_string(r.ls_nodes), fixed(per_ray(r.exact_work_units(), ray_count), 1),
                      fixed(100.0 * r.share_below_ls(), 1) + " %", fixed(per_ray(r.oracle_work_units(), ray_count), 1),
                      fixed(per_ray(r.traced_work_units(), ray_count), 1), fixed(per_ray(double(r.exact_work.lookups), ray_count), 2),
                      fixed(per_ray(double(lookups), ray_count), 2),
                      lookups ? fixed(100.0 * double(r.traced.accepted) / double(lookups), 1) + " %" : "-",
                      fixed(r.bound(), 2) + "x", fixed(r.achieved(), 2) + "x"});
  }
  return t;
}

nlohmann::json BoundStudy::json() const {
  nlohmann::json rows_json = nlohmann::json::array();
  for (const BoundRow& r : rows) {
    auto work = [&](const TraceWorkTotals& w) {
      return nlohmann::json{{"box_tests", w.box_tests},
                            {"triangle_tests", w.triangle_tests},
                            {"lookups", w.lookups},
                            {"box_tests_in_ls", w.box_tests_in_ls},
                            {"triangle_tests_in_ls", w.triangle_tests_in_ls}};
    };
    rows_json.push_back({{"structure", r.structure},
                         {"exact_structure", r.exact},
                         {"ls_nodes", r.ls_nodes},
                         {"exact_work_per_ray", per_ray(r.exact_work_units(), ray_count)},
                         {"oracle_work_per_ray", per_ray(r.oracle_work_units(), ray_count)},
                         {"ls_work_per_ray", per_ray(r.traced_work_units(), ray_count)},
                         {"share_below_ls", r.share_below_ls()},
                         {"bound", r.bound()},
                         {"achieved", r.achieved()},
                         {"exact_walk", work(r.exact_work)},
                         {"ls_walk", work(r.traced_work)},
                         {"ls_accepted", r.traced.accepted},
                         {"ls_empty", r.traced.empty}});
  }
  return {{"scene", scene},
          {"rays", rays},
          {"ray_count", ray_count},
          {"work_weights", {{"box_test", 1.0}, {"triangle_test", kTriangleTestWork}, {"lookup", kLookupWork}}},
          {"rows", rows_json}};
}

void write_bound_study(const std::string& dir, const BoundStudy& study) {
  std::filesystem::create_directories(dir);
  write_text_file(dir + "/bound.md", study.table().markdown());
  write_text_file(dir + "/bound.csv", study.table().csv());
  write_text_file(dir + "/bound.json", study.json().dump(2) + "\n");
}

}  // namespace ls
