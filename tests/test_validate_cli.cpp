// linespace-validate end to end: bad input exits 2 with one line, and each study writes the files and
// keys docs/usage.md promises, with figures that must hold by construction.
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <fstream>

using namespace test_support;
namespace fs = std::filesystem;

namespace {

Run validate(const std::string& args) { return run_program(LINESPACE_VALIDATE, args, "validate_cli"); }
fs::path temp(const std::string& name) { return temp_path("validate_cli", name); }

}  // namespace

TEST_CASE("linespace-validate: bad scenes, structures, sizes and flags exit 2 with a one-line reason", "[cli]") {
  fs::create_directories(temp(""));
  { std::ofstream(temp("broken.gltf")) << "{ not json"; }
  const std::array<std::string, 43> cases = {
      "rmse --scene /nonexistent.glb",
      "rmse --scene " + temp("broken.gltf").string(),
      "rmse --scene builtin:nothing",
      "rmse --structures f-ls:8",
      "rmse --structures f-ls:8:6,",
      "rmse --size 0x10",
      "rmse --size 12",
      "rmse --bounces 0",
      "rmse --device quantum",
      "sweep --depths 0,99",
      "sweep --families bvh",
      "sweep --start-bounce 5 --bounces 3",
      "sweep --angles 30 --ls-angle 45",  // two flags for one angle
      "sweep --behinds exact --ls-behind reverse",
      "sweep --behinds exact,ahead",
      "sweep --min-triangles 8 --ls-min-triangles 0",
      "sweep --min-triangles 8,x",
      "rmse --timing-rounds 0",
      "policy --timing-rounds 3",  // policy times round-robin, by --repeat
      "paper --tables 5",
      "paper --subdivisions 7",
      "policy --thresholds 0",
      "policy --thresholds -0.5",
      "policy --thresholds nan",
      "policy --thresholds 0.1,",
      "policy --start-bounces 0",
      "policy --start-bounces 4 --bounces 3",
      "policy --structure octree",
      "policy --repeat 0",
      "rmse --heatmap-max nan",  // NaN compares false with every bound
      "paper --heatmap-max nan",
      "sweep --ls-angle nan",
      "sweep --angles nan",
      "policy --start-bounces ''",  // an empty value (an unset variable) is not the flag left out
      "rmse --seed ''",
      "rmse --threads -2",
      "sweep --threads 1048576",  // more threads than this process's CPUs
      "bound --structures bvh",   // an exact structure has nothing to bound
      "bound --structures f-ls:3:4,2l-bvh",
      "bound --kind shadow",
      "bound --count 0",
      "bound --rays /nonexistent.rays",
      "bound --traversal fast",  // the study always counts on the reference kernels
  };
  for (const std::string& c : cases) {
    INFO(c);
    const Run r = validate(c + " --out " + temp("unused").string());
    REQUIRE(r.status == 2);
    REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    REQUIRE(r.err.rfind("linespace-validate: ", 0) == 0);
  }
  REQUIRE(validate("").status == 2);
}

TEST_CASE("linespace-validate: bad --spp, --auto-rel-stderr and --auto-seconds exit 2 with a one-line reason", "[cli]") {
  for (const char* c : {"rmse --spp 0", "rmse --spp 65537", "rmse --spp 4x", "rmse --spp automatic", "rmse --spp ''",
                        "sweep --spp auto --auto-rel-stderr 0", "sweep --spp auto --auto-rel-stderr 1",
                        "paper --spp auto --auto-rel-stderr -0.1", "budget --spp auto --auto-rel-stderr nan",
                        "policy --spp auto --auto-seconds 0", "rmse --spp auto --auto-seconds -5",
                        "rmse --spp 8 --auto-seconds 30", "rmse --auto-rel-stderr 0.2",
                        "bound --spp auto", "hits --spp auto", "candidates --spp auto"}) {
    INFO(c);
    const Run r = validate(std::string(c) + " --out " + temp("unused").string());
    REQUIRE(r.status == 2);
    REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    REQUIRE(r.err.rfind("linespace-validate: ", 0) == 0);
  }
  REQUIRE_FALSE(fs::exists(temp("unused") / "rmse.json"));
}

TEST_CASE("linespace-validate rmse.json rows carry rmse_bias and its standard error, and --spp auto says why it stopped", "[cli]") {
  const fs::path out = temp("rmse_bias");
  const std::string common = " --scene builtin:cornell --structures f-ls:3:4 --size 16x16 --bounces 2 --ls-min-triangles 0 --out ";
  // 8 spp: at 4 the second row's errors fell in one half per pixel only (rmse_bias undetermined, null).
  Run r = validate("rmse --spp 8" + common + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  nlohmann::json j = nlohmann::json::parse(slurp(out / "rmse.json"));
  REQUIRE(j["rows"].size() == 2);
  REQUIRE(j["spp_auto"].is_null());
  for (const auto& row : j["rows"]) {
    for (const char* key : {"rmse", "rmse_bias", "rmse_bias_stderr", "noise_floor"}) REQUIRE(row[key].is_number());
    REQUIRE(row["rmse_bias"].get<double>() >= 0.0);
    REQUIRE(row["rmse_bias_stderr"].get<double>() >= 0.0);
    REQUIRE(row["spp"] == 8);
    REQUIRE_FALSE(row.contains("spp_stop"));
  }
  const std::string md = slurp(out / "rmse.md"), csv = slurp(out / "rmse.csv");
  REQUIRE(md.find("rmse_bias from bounce 1") != std::string::npos);
  REQUIRE(md.find("noise floor") != std::string::npos);
  REQUIRE(csv.find("rmse,rmse_bias,rmse_bias_stderr,noise_floor,spp,spp_stop") != std::string::npos);

  // 1 sample per pixel has no second half: the keys are there, null.
  r = validate("rmse --spp 1" + common + out.string());
  REQUIRE(r.status == 0);
  j = nlohmann::json::parse(slurp(out / "rmse.json"));
  for (const auto& row : j["rows"]) {
    REQUIRE(row["rmse_bias"].is_null());
    REQUIRE(row["rmse_bias_stderr"].is_null());
  }

  r = validate("rmse --spp auto --auto-rel-stderr 0.5 --auto-seconds 20" + common + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  j = nlohmann::json::parse(slurp(out / "rmse.json"));
  REQUIRE(j["spp_auto"]["rel_stderr"] == 0.5);
  REQUIRE(j["spp_auto"]["seconds"] == 20.0);
  for (const auto& row : j["rows"]) {
    const std::string stop = row["spp_stop"];
    REQUIRE((stop == "converged" || stop == "time budget" || stop == "max spp"));
    REQUIRE(row["spp"].get<int>() >= 4);
    REQUIRE(r.err.find(stop) != std::string::npos);  // said on stderr too
    if (stop == "converged") REQUIRE(row["rmse_bias_stderr"].get<double>() <= 0.5 * row["rmse_bias"].get<double>());
  }
  REQUIRE(slurp(out / "rmse.md").find("--spp auto stopped") != std::string::npos);
}

TEST_CASE("linespace-validate bound and hits refuse rays over --max-memory before building anything", "[cli]") {
  // 200,000 rays made here: up to 65 B a ray for bound (the generator's peak), 72 B for hits (the
  // rays and two hit arrays): 13 and 14.4 MB, over 8 MB.  Refused before a Vulkan device is asked.
  const std::array<std::pair<std::string, std::string>, 2> cases = {{
      {"bound --scene builtin:cornell --count 200000 --max-memory 8 --out " + temp("unused").string(),
       "bound: 200000 rays and their hits take up to 13 MiB"},
      {"hits --scene builtin:cornell --count 200000 --max-memory 8", "hits: 200000 rays and their hits take up to 14 MiB"},
  }};
  for (const auto& [args, what] : cases) {
    const Run r = validate(args);
    INFO(args << "\nstderr: " << r.err);
    REQUIRE(r.status == 2);
    REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    REQUIRE(r.err.find(what) != std::string::npos);
    REQUIRE(r.err.find("use fewer rays (--count) or raise --max-memory") != std::string::npos);
  }
  REQUIRE_FALSE(fs::exists(temp("unused") / "bound.json"));
}

TEST_CASE("linespace-validate rmse writes rmse.json with the documented keys and heat-maps", "[cli]") {
  const fs::path out = temp("rmse");
  const Run r = validate("rmse --scene builtin:generated:2000:4:1 --structures f-ls:4:4,2l-ls:0:4 --size 16x16 "
                         "--spp 1 --bounces 2 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "rmse.json"));
  REQUIRE(j["rows"].size() == 4);
  for (const auto& row : j["rows"]) {
    for (const char* key : {"structure", "start_bounce", "rmse", "rmse_bias", "rmse_bias_stderr", "mrays_per_s", "bytes"})
      REQUIRE(row.contains(key));
    REQUIRE(row["contribution_rmse"].size() == 3);
    // Bounces before the switch are exact.
    for (int b = 0; b < row["start_bounce"].get<int>(); ++b) REQUIRE(row["contribution_rmse"][size_t(b)] == 0.0);
  }
  for (const char* f : {"rmse.md", "rmse.csv", "reference.png", "f-ls_4_4_from_bounce_1_heatmap.png",
                        "2l-ls_0_4_from_bounce_2_side_by_side.png"})
    REQUIRE(fs::file_size(out / f) > 0);
}

TEST_CASE("linespace-validate bound writes bound.json whose bounds follow from its work counts", "[cli]") {
  const fs::path out = temp("bound");
  const Run r = validate("bound --scene builtin:cornell --structures f-ls:3:4,2l-ls:0:3 --count 2000 --seed 3 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  REQUIRE(r.out.find("| f-ls:3:4 vs bvh |") != std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "bound.json"));
  REQUIRE(j["ray_count"] == 2000);
  REQUIRE(j["rows"].size() == 2);
  REQUIRE(j["rows"][1]["exact_structure"] == "2l-bvh");
  for (const auto& row : j["rows"]) {
    const double exact = row["exact_work_per_ray"], oracle = row["oracle_work_per_ray"], traced = row["ls_work_per_ray"];
    REQUIRE(exact > 0.0);
    REQUIRE(row["bound"].get<double>() == Approx(exact / oracle));
    REQUIRE(row["achieved"].get<double>() == Approx(exact / traced));
    const auto& walk = row["exact_walk"];
    REQUIRE(walk["box_tests_in_ls"].get<uint64_t>() < walk["box_tests"].get<uint64_t>());
    REQUIRE(exact * 2000 == Approx(walk["box_tests"].get<double>() + 2.3 * walk["triangle_tests"].get<double>()));
  }
  for (const char* f : {"bound.md", "bound.csv"}) REQUIRE(fs::file_size(out / f) > 0);
}

TEST_CASE("linespace-validate sweep writes the data and the trade-off plot", "[cli]") {
  const fs::path out = temp("sweep");
  const Run r = validate("sweep --scene builtin:generated:2000:4:1 --depths 0,3 --subdivisions 3 --angles 0,45 "
                         "--size 16x16 --spp 1 --bounces 1 --timing-rounds 1 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "sweep.json"));
  REQUIRE(j["points"].size() == 8);  // 2 angles x 2 families x 2 depths x 1 subdivision
  // The front flags agree with the figures written beside them (the exact F-BVH takes part).
  for (const auto& p : j["points"]) {
    if (p["angle"] == 0.0) REQUIRE(p["rmse"] == 0.0);  // refusing every approximation is exact
    // The speed-up is over the exact F-BVH timed beside the point (one round: no median to take).
    REQUIRE(p["speedup_vs_bvh"].get<double>() == Approx(p["mrays_per_s"].get<double>() / p["exact_mrays_per_s"].get<double>()));
    const double r = p["rmse"], m = p["speedup_vs_bvh"];
    bool dominated = 1.0 >= m && (1.0 > m || r > 0.0);
    for (const auto& q : j["points"]) {
      const double qr = q["rmse"], qm = q["speedup_vs_bvh"];
      if (&q != &p && qm >= m && qr <= r && (qm > m || qr < r)) dominated = true;
    }
    REQUIRE(p["pareto"].get<bool>() == !dominated);
  }
  REQUIRE(fs::file_size(out / "tradeoff.png") > 1000);
  REQUIRE(fs::file_size(out / "tradeoff.svg") > 1000);
}

TEST_CASE("linespace-validate sweep over the behind mode and the smallest subtree", "[cli]") {
  const fs::path out = temp("sweep-behinds");
  const Run r = validate("sweep --scene builtin:generated:2000:4:1 --families f-ls --depths 3 --subdivisions 3 "
                         "--behinds exact,reverse --min-triangles 0,1000000 --ls-angle 60 --size 16x16 --spp 1 "
                         "--bounces 1 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "sweep.json"));
  REQUIRE(j["points"].size() == 4);  // 2 smallest subtrees x 2 modes
  const std::vector<std::pair<int, std::string>> order = {{0, "exact"}, {0, "reverse"}, {1000000, "exact"}, {1000000, "reverse"}};
  for (size_t i = 0; i < order.size(); ++i) {
    const auto& p = j["points"][i];
    INFO(p.dump());
    REQUIRE(p["min_triangles"] == order[i].first);
    REQUIRE(p["behind"] == order[i].second);
    if (order[i].first == 0) {
      REQUIRE(p["ls_nodes"].get<int>() > 0);
    } else {  // no subtree is that large: no Line Space, the exact image
      REQUIRE(p["ls_nodes"] == 0);
      REQUIRE(p["rmse"] == 0.0);
    }
  }
  REQUIRE(fs::file_size(out / "tradeoff.png") > 1000);
  REQUIRE(slurp(out / "sweep.csv").find("behind,min_triangles") != std::string::npos);
}

TEST_CASE("linespace-validate sweep without --angles sweeps at --ls-angle", "[cli]") {
  // At 60 degrees this small sweep errs somewhere (with reverse, whose first candidates answer rays
  // from inside a box too); at 0 every lookup is refused and every point is exact.
  for (const double angle : {60.0, 0.0}) {
    const fs::path out = temp("sweep-ls-angle");
    const Run r = validate("sweep --scene builtin:generated:2000:4:1 --depths 3 --subdivisions 3 --ls-angle " +
                           std::to_string(angle) + " --ls-behind reverse --size 16x16 --spp 1 --bounces 1 --no-plot --out " +
                           out.string());
    INFO(r.err);
    REQUIRE(r.status == 0);
    const nlohmann::json j = nlohmann::json::parse(slurp(out / "sweep.json"));
    REQUIRE(j["points"].size() == 2);  // 2 families x 1 depth x 1 subdivision
    double largest = 0.0;
    for (const auto& p : j["points"]) {
      CHECK(p["angle"] == angle);
      largest = std::max(largest, p["rmse"].get<double>());
    }
    if (angle == 0.0) CHECK(largest == 0.0);  // refusing every approximation is exact
    else CHECK(largest > 0.0);
  }
}

TEST_CASE("linespace-validate paper prints the three tables and the claims", "[cli]") {
  const fs::path out = temp("paper");
  const Run r = validate("paper --scenes builtin:generated:1500:4:1 --subdivisions 6 --size 12x12 --spp 1 --out " +
                         out.string() + " --max-memory 200");
  INFO(r.err);
  REQUIRE(r.status == 0);
  for (const char* heading : {"Table 2 analogue", "Table 3 analogue", "Table 4 analogue", "claims hold here"})
    REQUIRE(r.out.find(heading) != std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "paper.json"));
  REQUIRE(j["scenes"].size() == 1);
  const auto& t4 = j["scenes"][0]["table4"];
  REQUIRE(t4.size() == 7);
  REQUIRE(t4[0]["schedule"] == "bvh");
  REQUIRE(t4[0]["rmse"] == 0.0);  // the all-exact schedule against itself
  REQUIRE(j["claims"].size() >= 6);
  for (const auto& c : j["claims"]) REQUIRE(c["checked"].get<int>() >= c["held"].get<int>());
}

// A study checks its --out before any work: it once ran to its end and failed there on a file.
TEST_CASE("linespace-validate studies refuse an --out that is a file before any work", "[cli]") {
  const fs::path file = temp("a_file");
  fs::create_directories(file.parent_path());
  std::ofstream(file) << "not a folder\n";
  for (const char* study : {"rmse", "sweep", "paper", "budget", "policy", "bound"}) {
    const auto start = std::chrono::steady_clock::now();
    const Run r = validate(std::string(study) + " --out " + file.string());
    INFO(study << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(r.err.find("is a file, not a folder") != std::string::npos);
    CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(5));
  }
}

// Every point refused (over --max-memory): the sweep says so, where the plot step once took the blame.
TEST_CASE("linespace-validate sweep whose every configuration is refused says so and exits 2", "[cli]") {
  const Run r = validate("sweep --scene builtin:cornell --families f-ls --depths 8 --subdivisions 10 --size 8x8 --spp 2 "
                         "--bounces 1 --timing-rounds 1 --max-memory 20 --out " + temp("all_refused").string());
  INFO(r.err);
  CHECK(r.status == 2);
  CHECK(r.err.find("every configuration was refused (f-ls:8:10: structure 'f-ls:8:10' would take up to") != std::string::npos);
  CHECK(r.err.find("matplotlib") == std::string::npos);
  CHECK(fs::exists(temp("all_refused") / "sweep.json"));  // the refusals are data too
}

// Table 2 builds and renders nothing: its rows carry the builds' figures and null for a render's, and
// the reference is null (they were zeros, which a script would read as exact results).
TEST_CASE("linespace-validate paper --tables 2 writes no render figures it did not measure", "[cli]") {
  const fs::path out = temp("paper_t2");
  const Run r = validate("paper --scenes builtin:cornell --tables 2 --subdivisions 6 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const nlohmann::json study = nlohmann::json::parse(slurp(out / "paper.json"))["scenes"][0]["study"];
  CHECK(study["reference"].is_null());
  REQUIRE(!study["rows"].empty());
  for (const auto& row : study["rows"]) {
    INFO(row.dump());
    CHECK(row["bytes_ls"].get<double>() > 0.0);
    CHECK(row["build_seconds"].get<double>() > 0.0);
    for (const char* key : {"rmse", "rmse_bias", "spp", "mrays_per_s", "speedup_vs_bvh"}) CHECK(row[key].is_null());
  }
}

TEST_CASE("linespace-validate policy writes policy.{md,csv,json} with both policies and the equal-speed comparison", "[cli]") {
  const fs::path out = temp("policy");
  const Run r = validate("policy --scene builtin:cornell --structure f-ls:3:6 --thresholds 0.3,2 --start-bounces 2 --repeat 2 "
                         "--size 16x16 --spp 1 --bounces 2 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "policy.json"));
  REQUIRE(j["structure"] == "f-ls:3:6");
  REQUIRE(j["repeats"] == 2);
  REQUIRE(j["points"].size() == 3);
  for (const auto& p : j["points"]) {
    for (const char* key : {"policy", "rmse", "mrays_per_s", "fraction_on_x", "rays_on_x", "indirect_rays"}) REQUIRE(p.contains(key));
    REQUIRE(p["fraction_on_x"].get<double>() == double(p["rays_on_x"].get<uint64_t>()) / double(p["indirect_rays"].get<uint64_t>()));
  }
  // T = 2 is above every throughput: every indirect ray on X.
  REQUIRE(j["points"][2]["threshold"] == 2.0);
  REQUIRE(j["points"][2]["fraction_on_x"] == 1.0);
  REQUIRE(j["comparisons"].size() == 1);
  REQUIRE(j["comparisons"][0]["start_bounce"] == 2);
  REQUIRE(fs::file_size(out / "policy.md") > 0);
  REQUIRE(fs::file_size(out / "policy.csv") > 0);
}

TEST_CASE("linespace-validate budget compares each uniform 2L-LS with a 2l-ls:auto of its bytes", "[cli]") {
  const fs::path out = temp("budget");
  const Run r = validate("budget --scene builtin:cornell --uniform 2l-ls:2:4,2l-ls:0:6 --size 16x16 --spp 4 --bounces 2 --out " +
                         out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const nlohmann::json j = nlohmann::json::parse(slurp(out / "budget.json"));
  REQUIRE(j["rows"].size() == 2);
  REQUIRE(j["rows"][0]["uniform_structure"] == "2l-ls:2:4");
  REQUIRE(j["rows"][1]["uniform_structure"] == "2l-ls:0:6");
  for (const auto& row : j["rows"]) {
    INFO(row["uniform_structure"]);
    const auto &uniform = row["uniform"], &planned = row["auto"], &plan = planned["plan"];
    // The budget is the uniform structure's Line Space, and the plan spends no more, exactly as predicted.
    CHECK(row["budget_bytes"] == uniform["bytes_ls"]);
    CHECK(plan["budget_bytes"] == row["budget_bytes"]);
    CHECK(planned["bytes_ls"].get<size_t>() <= row["budget_bytes"].get<size_t>());
    CHECK(planned["bytes_ls"] == planned["predicted_bytes"]);
    size_t objects = plan["fixed_bytes"].get<size_t>();
    for (const auto& o : plan["objects"]) objects += o["bytes"].get<size_t>();
    CHECK(objects == plan["predicted_bytes"].get<size_t>());
    CHECK(plan["objects"].size() == 10);  // cornell's objects
    for (const char* key : {"rmse_from_bounce", "rmse_bias_from_bounce", "rmse_bias_stderr_from_bounce", "noise_floor_from_bounce",
                            "spp_from_bounce"}) {
      REQUIRE(uniform[key].size() == 2);
      REQUIRE(planned[key].size() == 2);
    }
    // A plan that is the uniform structure itself renders its images.
    if (plan["reference_chosen"].get<bool>()) CHECK(planned["rmse_from_bounce"] == uniform["rmse_from_bounce"]);
    // The verdict follows its rule: rmse_bias where both are estimated, else the RMSE, lower at every start bounce.
    bool lower = true;
    for (size_t k = 0; k < 2; ++k) {
      const bool estimated = !planned["rmse_bias_from_bounce"][k].is_null() && !uniform["rmse_bias_from_bounce"][k].is_null();
      const char* figure = estimated ? "rmse_bias_from_bounce" : "rmse_from_bounce";
      lower = lower && planned[figure][k].get<double>() < uniform[figure][k].get<double>();
    }
    CHECK(row["lower_rmse_at_every_start_bounce"] == lower);
  }
  CHECK(fs::file_size(out / "budget.md") > 0);
  std::ifstream csv(out / "budget.csv");
  CHECK(std::count(std::istreambuf_iterator<char>(csv), std::istreambuf_iterator<char>(), '\n') == 1 + 2 * 2);
}
