// linespace-cpu end to end: the file formats, the JSON keys of docs/design.md §9, and exit status 2 with a
// one-line reason on bad input.
#include "common/base/ray_files.h"
#include "cpu/trace/embree_tracer.h"
#include "tests/gltf_writer.h"
#include "tests/test_helpers.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

using namespace test_support;
namespace fs = std::filesystem;

namespace {

// Each test process gets its own folder: ctest runs test cases in parallel.
fs::path temp(const std::string& name) { return temp_path("cli_test", name); }

Run run(const std::string& args) { return run_program(LINESPACE_CPU, args, "cli_test"); }

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

size_t line_count(const std::string& s) { return size_t(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST_CASE("bad input exits 2 with a one-line reason", "[cli]") {
  fs::create_directories(temp(""));
  write_text(temp("bad.gltf"), "{ this is not json");
  write_text(temp("nan.obj"), "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
  write_text(temp("empty.obj"), "");
  write_text(temp("odd.rays"), std::string(33, '\0'));
  const std::array<std::string, 46> cases = {
      "build --scene /nonexistent/scene.gltf",
      "build --scene " + temp("bad.gltf").string(),
      "build --scene " + temp("nan.obj").string(),
      "build --scene " + temp("empty.obj").string(),
      "build --scene builtin:nope",
      "build --scene scene.xyz",
      "build --structure octree",
      "build --structure f-ls:8",
      "render --schedule bvh,,bvh --size 8x8 --out " + temp("r").string(),
      "render --size 0x10 --out " + temp("r").string(),
      "render --size banana --out " + temp("r").string(),
      "render --spp 0 --size 8x8 --out " + temp("r").string(),
      "render --throughput-switch 0:bvh --size 8x8 --out " + temp("r").string(),
      "render --throughput-switch -0.5:bvh --size 8x8 --out " + temp("r").string(),
      "render --throughput-switch nan:bvh --size 8x8 --out " + temp("r").string(),
      "render --throughput-switch 0.5:octree --size 8x8 --out " + temp("r").string(),
      "render --throughput-switch 0.5 --size 8x8 --out " + temp("r").string(),
      "trace --rays " + temp("odd.rays").string() + " --hits " + temp("h").string(),
      "trace --rays /nonexistent.rays --hits " + temp("h").string(),
      "rays --kind sideways --count 10 --out " + temp("x.rays").string(),
      "frobnicate",
      "build --structure 2l-ls:auto",                       // no --ls-budget
      "build --structure 2l-ls:4:6 --ls-budget 10",          // --ls-budget without 2l-ls:auto
      "build --structure 2l-ls:auto --ls-budget 0.001",      // below the fixed part
      "build --structure 2l-ls:auto --ls-budget 1e-9",       // under a byte: below the fixed part too, not "no budget"
      "build --structure 2l-ls:auto --ls-budget 10 --ls-budget-rays 0",
      "build --exact-width 16",
      "build --ls-behind sideways",
      "build --ls-leave-reach -1",
      "trace --ls-leave-reach nan --rays /nonexistent.rays --hits " + temp("h").string(),
      "build --ls-leave-reach 0.5x",
      "bench --exact-width 0 --count 10",
      "build --threads -1",
      "bench --threads 1048576 --count 10",  // more threads than this process's CPUs
      // NaN compares false with every bound, so range checks once let it through.
      "render --ls-angle nan --size 8x8 --out " + temp("r").string(),
      "build --max-memory nan",
      "build --max-memory inf",
      "build --structure 2l-ls:auto --ls-budget nan",
      "rays --max-memory nan --count 10 --out " + temp("x.rays").string(),
      // An empty value (an unset shell variable) once read as the flag not given: a whole render.
      "render --shard '' --size 8x8 --out " + temp("r").string(),
      "render --tiles '' --size 8x8 --out " + temp("r").string(),
      "render --frames '' --fps 24 --size 8x8 --out " + temp("r").string(),
      "render --throughput-switch '' --size 8x8 --out " + temp("r").string(),
      "rays --seed '' --count 10 --out " + temp("x.rays").string(),
      "render --frames 0:1 --animation -1 --size 8x8 --out " + temp("r").string(),  // once read as 2^64 - 1
      "rays --kind shadow --count 1 --out " + temp("x.rays").string(),  // one origin: no segment (zero length once)
  };
  for (const std::string& args : cases) {
    const Run r = run(args);
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.rfind("linespace-cpu: ", 0) == 0);
  }
}

TEST_CASE("rays, trace and build agree with the file formats and JSON keys", "[cli]") {
  fs::create_directories(temp(""));
  const std::string rays = temp("d.rays").string(), hits = temp("d.hits").string();
  Run r = run("rays --scene builtin:cornell --kind diffuse --count 1000 --seed 3 --out " + rays);
  REQUIRE(r.status == 0);
  REQUIRE(fs::file_size(rays) == 1000u * 32u);
  r = run("trace --scene builtin:cornell --structure 2l-bvh --rays " + rays + " --hits " + hits);
  REQUIRE(r.status == 0);
  REQUIRE(fs::file_size(hits) == 1000u * 20u);
  // A hit has a finite t and valid ids; a miss (+inf, 0xFFFFFFFF) is a ray that leaves cornell's room
  // through its open front (+z), the only way out.
  std::ifstream f(hits, std::ios::binary), rf(rays, std::ios::binary);
  int misses = 0;
  for (int i = 0; i < 1000; ++i) {
    float t, u, v, ray[8];
    uint32_t inst, tri;
    f.read(reinterpret_cast<char*>(&t), 4).read(reinterpret_cast<char*>(&inst), 4).read(reinterpret_cast<char*>(&tri), 4);
    f.read(reinterpret_cast<char*>(&u), 4).read(reinterpret_cast<char*>(&v), 4);
    rf.read(reinterpret_cast<char*>(ray), sizeof ray);
    if (tri == 0xFFFFFFFFu) {
      ++misses;
      REQUIRE(std::isinf(t));
      REQUIRE(inst == 0xFFFFFFFFu);
      REQUIRE(ray[6] > 0.0f);  // dz
      continue;
    }
    REQUIRE(std::isfinite(t));
    REQUIRE(u >= 0.0f);
    REQUIRE(v >= 0.0f);
    REQUIRE(u + v <= 1.0001f);
  }
  REQUIRE(f.good());
  REQUIRE(rf.good());
  CHECK(misses < 500);

  r = run("build --scene builtin:cornell --structure 2l-bvh --json");
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"triangles", "objects", "instances", "nodes", "ls_nodes", "shafts_per_ls", "bytes_total", "bytes_ls",
                          "build_seconds"})
    CHECK(j.contains(key));
  CHECK(j["triangles"].get<int>() > 0);

  // 2l-ls:auto prints its plan: every object with its choice, predicted and measured bytes alike.
  r = run("build --scene builtin:cornell --structure 2l-ls:auto --ls-budget 1 --ls-budget-rays 2000 --json");
  REQUIRE(r.status == 0);
  const auto a = nlohmann::json::parse(r.out);
  REQUIRE(a.contains("ls_plan"));
  const auto& plan = a["ls_plan"];
  for (const char* key : {"budget_bytes", "fixed_bytes", "predicted_bytes", "reference", "plan", "uniform", "pilot_rays", "objects"})
    CHECK(plan.contains(key));
  CHECK(plan["predicted_bytes"] == a["bytes_ls"]);
  CHECK(plan["budget_bytes"].get<size_t>() == 1000000u);
  CHECK(a["bytes_ls"].get<size_t>() <= 1000000u);
  CHECK(plan["objects"].size() == a["objects"].get<size_t>());
  for (const auto& o : plan["objects"])
    for (const char* key : {"mesh", "name", "triangles", "chosen", "reference", "bytes", "pilot_error", "pilot_saved_work", "reason"})
      CHECK(o.contains(key));
}

TEST_CASE("trace --ls-behind reaches the lookup: exact, empty and reverse answer the rays from inside the box as documented", "[cli]") {
  fs::create_directories(temp(""));
  const std::string rays = temp("behind.rays").string(), hits = temp("behind.hits").string();
  REQUIRE(run("rays --scene builtin:cornell --kind diffuse --count 1000 --seed 3 --out " + rays).status == 0);
  // f-ls:0:4: one Line Space, at the root, which holds every origin: one lookup a ray, its first
  // candidate mostly behind the origin.
  struct Counted {
    unsigned lookups = 0, empty = 0, accepted = 0, behind = 0;
  };
  auto trace = [&](const std::string& mode) {
    const Run r = run("trace --scene builtin:cornell --structure f-ls:0:4 --ls-behind " + mode + " --rays " + rays + " --hits " + hits);
    REQUIRE(r.status == 0);
    Counted c;
    const std::string printed = r.out + r.err;
    const size_t at = printed.find("line space:");
    REQUIRE(at != std::string::npos);
    REQUIRE(std::sscanf(printed.c_str() + at, "line space: %u lookups, %u empty shafts, %u accepted, refused %*u (angle %*u, before the window %u",
                        &c.lookups, &c.empty, &c.accepted, &c.behind) == 4);
    return c;
  };
  const Counted exact = trace("exact"), empty = trace("empty"), reverse = trace("reverse");
  INFO("exact " << exact.empty << " empty, " << exact.accepted << " accepted, " << exact.behind << " behind; empty mode "
                << empty.empty << ", " << empty.accepted << ", " << empty.behind << "; reverse " << reverse.empty << ", "
                << reverse.accepted << ", " << reverse.behind);
  REQUIRE(exact.lookups == 1000u);
  REQUIRE(empty.lookups == 1000u);
  CHECK(exact.behind > 500u);
  CHECK(empty.empty > exact.empty);                                    // the reverse shaft's "nothing ahead"
  CHECK(empty.empty < reverse.empty);                                  // some of reverse's: the surface the ray leaves
  CHECK(empty.accepted == exact.accepted);                             // its candidates never answer
  // The rest refused as behind: from inside the box exact refuses every shaft that is not empty as
  // behind, where empty names the other reasons (angle, past the window, parallel).
  CHECK(exact.empty + exact.behind + exact.accepted <= exact.lookups);
  CHECK(empty.behind + (empty.empty - exact.empty) <= exact.behind);
  CHECK(empty.behind + (empty.empty - exact.empty) + 10u >= exact.behind);
  CHECK(reverse.accepted > exact.accepted);
  CHECK(reverse.behind < empty.behind);
  // --ls-leave-reach: the farther off its triangle a reverse plane hit may lie, the more "nothing
  // ahead" answers; cornell's walls are two triangles each, so some lie on the wall's other one.
  const Counted on_triangle = trace("empty --ls-leave-reach 0"), in_plane = trace("empty --ls-leave-reach inf");
  INFO("empty mode at reach 0: " << on_triangle.empty << ", at inf: " << in_plane.empty);
  CHECK(on_triangle.empty <= empty.empty);
  CHECK(empty.empty <= in_plane.empty);
  CHECK(on_triangle.empty < in_plane.empty);
  CHECK(in_plane.empty < reverse.empty);  // still only the surface the ray leaves
  CHECK(on_triangle.accepted == exact.accepted);
  CHECK(in_plane.accepted == exact.accepted);
}

TEST_CASE("trace --against counts the rays whose hit differs from another hit file's, and refuses a file of other rays", "[cli]") {
  fs::create_directories(temp(""));
  const std::string rays = temp("against.rays").string(), exact = temp("against-exact.hits").string(),
                    approx = temp("against-ls.hits").string(), short_file = temp("against-short.hits").string();
  REQUIRE(run("rays --scene builtin:cornell --kind diffuse --count 2000 --seed 4 --out " + rays).status == 0);
  REQUIRE(run("trace --scene builtin:cornell --structure bvh --rays " + rays + " --hits " + exact).status == 0);
  auto other_hits = [](const Run& r) {
    const std::string printed = r.out + r.err;
    const size_t at = printed.find("against ");
    REQUIRE(at != std::string::npos);
    const size_t of = printed.find(": ", at);
    REQUIRE(of != std::string::npos);
    unsigned other = 0, total = 0;
    REQUIRE(std::sscanf(printed.c_str() + of, ": %u of %u rays", &other, &total) == 2);
    REQUIRE(total == 2000u);
    return other;
  };
  // The approximation against the exact hits: the count the test finds comparing the files itself.
  const Run traced = run("trace --scene builtin:cornell --structure f-ls:3:3 --ls-min-triangles 0 --rays " + rays + " --hits " +
                     approx + " --against " + exact);
  REQUIRE(traced.status == 0);
  const std::vector<lsk::Hit> a = ls::read_hits(exact), b = ls::read_hits(approx);
  REQUIRE(a.size() == 2000u);
  REQUIRE(b.size() == 2000u);
  unsigned differ = 0;
  for (size_t i = 0; i < a.size(); ++i) differ += a[i].instance != b[i].instance || a[i].triangle != b[i].triangle;
  CHECK(differ > 0);
  CHECK(other_hits(traced) == differ);
  // The exact structure against itself: none.
  const Run same = run("trace --scene builtin:cornell --structure bvh --rays " + rays + " --hits " + approx + " --against " + exact);
  REQUIRE(same.status == 0);
  CHECK(other_hits(same) == 0u);
  // A hit file of other rays, or none: exit 2 with one line naming the file.
  std::vector<lsk::Hit> fewer(a.begin(), a.end() - 1);
  ls::write_hits(short_file, fewer);
  // The right count of records that are no hits of this scene: an instance past its 10, a NaN t, a
  // miss that names a triangle (random bytes were once compared as hits).
  std::vector<std::string> not_hits;
  for (int k = 0; k < 3; ++k) {
    std::vector<lsk::Hit> h = a;
    if (k == 0) h[5].instance = 10;
    if (k == 1) h[5].t = std::nanf("");
    if (k == 2) h[5] = lsk::Hit{std::numeric_limits<float>::infinity(), lsk::LS_INVALID, 7u, 0.0f, 0.0f};
    not_hits.push_back(temp("not_hits_" + std::to_string(k) + ".hits").string());
    ls::write_hits(not_hits.back(), h);
  }
  for (const std::string& bad : {short_file, temp("no-such.hits").string(), not_hits[0], not_hits[1], not_hits[2]}) {
    const Run r = run("trace --scene builtin:cornell --structure bvh --rays " + rays + " --hits " + approx + " --against " + bad);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find(bad) != std::string::npos);
  }
}

TEST_CASE("bench prints DESIGN 9's JSON keys for each structure and Embree, closest hit and occlusion", "[cli]") {
  for (const char* kind : {"diffuse", "shadow"}) {
    const Run r = run(std::string("bench --scene builtin:cornell --count 2000 --repeat 1 --structures 2l-bvh,f-ls:3:3 --json --kind ") + kind);
    REQUIRE(r.status == 0);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["rays"].get<size_t>() == 2000u);
    CHECK(j["any_hit"].get<bool>() == (std::string(kind) == "shadow"));
    REQUIRE(j["results"].size() == 3u);
    for (const auto& e : j["results"]) {
      for (const char* key : {"structure", "mrays_per_s", "ratio_vs_embree", "bytes"}) CHECK(e.contains(key));
      CHECK(e["mrays_per_s"].get<double>() > 0.0);
      if (e["structure"] != "embree") {
        CHECK(e["reference_mrays_per_s"].get<double>() > 0.0);
        CHECK(e["ratio_vs_fast_bvh"].is_null());  // no bvh in this run
      }
    }
    CHECK(j["results"][2]["structure"] == "embree");
    CHECK(j["results"][2]["ratio_vs_embree"].get<double>() == 1.0);
    // Embree's own choice is reported by name: one of its targets, never "best".
    const std::vector<std::string>& names = ls::embree_isa_names();
    CHECK(std::find(names.begin() + 1, names.end(), j["embree_isa"].get<std::string>()) != names.end());
  }
}

TEST_CASE("bench refuses structures that fit --max-memory one by one but not together", "[cli]") {
  // Each of bvh and 2l-bvh, with its fast path and Embree's scene, fits 8.5 MB on this scene; bench
  // holds both at once, and 2l-bvh's fast path bound does not fit beside bvh.  One thread: Embree's
  // build peak grows with its threads (about 3 MB on two here), which would make the answer the
  // machine's.
  const std::string args =
      "bench --threads 1 --scene builtin:generated:20000:7:3 --count 1000 --repeat 1 --max-memory 8.5 --structures ";
  for (const char* one : {"bvh", "2l-bvh"}) {
    const Run r = run(args + one);
    INFO(one << "\nstderr: " << r.err);
    CHECK(r.status == 0);
  }
  const Run both = run(args + "bvh,2l-bvh");
  INFO(both.err);
  CHECK(both.status == 2);
  CHECK(line_count(both.err) == 1);
  CHECK(both.err.find("structure '2l-bvh'") != std::string::npos);
  CHECK(both.err.find("bench holds its rays, hits and structures at once") != std::string::npos);
  CHECK(both.err.find("bench fewer --structures") != std::string::npos);
  CHECK(both.err.find("--max-memory") != std::string::npos);
}

TEST_CASE("bench counts its rays, hits and Embree's scene in --max-memory", "[cli]") {
  // bvh with a 4-wide order-free tree fits 5.6 MB on this scene (3.5 MB built; the fast path's
  // bound, checked before it is made, is larger at 8 wide: one 256-byte node per binary inner node);
  // Embree's scene (1.7 MB kept, more while it builds, on one thread as on many) does not fit the
  // 2 MB left: its memory monitor cancels the build.
  const Run embree = run(
      "bench --threads 1 --scene builtin:generated:20000:7:3 --count 1000 --repeat 1 --max-memory 5.6 --structures bvh "
      "--exact-width 4");
  INFO(embree.err);
  CHECK(embree.status == 2);
  CHECK(line_count(embree.err) == 1);
  CHECK(embree.err.find("Embree's scene would take more than") != std::string::npos);
  CHECK(embree.err.find("bench fewer --structures or raise --max-memory") != std::string::npos);
  CHECK(embree.out.empty());
  // 200,000 rays and their hits are 10.4 MB: refused before anything is built.
  const Run rays = run("bench --scene builtin:cornell --count 200000 --repeat 1 --max-memory 8 --structures bvh");
  INFO(rays.err);
  CHECK(rays.status == 2);
  CHECK(line_count(rays.err) == 1);
  CHECK(rays.err.find("200000 rays and their hits") != std::string::npos);
  CHECK(rays.err.find("--count") != std::string::npos);
}

TEST_CASE("rays, trace and bench refuse rays over --max-memory before loading or making anything", "[cli]") {
  const fs::path rays = temp("budget.rays");
  REQUIRE(run("rays --scene builtin:cornell --count 1000 --seed 5 --out " + rays.string()).status == 0);
  // Made here: up to 65 B a ray (the rays and a round of candidates), 65 MB for a million; a file's
  // 1,000 rays and their hits: 52 kB, over 0.05 MB.
  const std::array<std::tuple<std::string, std::string, std::string>, 4> cases = {{
      {"rays --scene builtin:cornell --count 1000000 --max-memory 10 --out " + temp("many.rays").string(), "rays: 1000000 rays take up to 62 MiB",
       "use fewer rays (--count)"},
      {"trace --scene builtin:cornell --structure bvh --max-memory 0.05 --rays " + rays.string() + " --hits " + temp("h.hits").string(),
       "trace: 1000 rays and their hits", "use a smaller ray file"},
      {"bench --scene builtin:cornell --structures bvh --max-memory 0.05 --rays " + rays.string(), "bench: 1000 rays and their hits",
       "use a smaller ray file"},
      {"bench --scene builtin:cornell --structures bvh --max-memory 10 --count 1000000", "bench: 1000000 rays and their hits",
       "use fewer rays (--count)"},
  }};
  for (const auto& [args, what, advice] : cases) {
    const Run r = run(args);
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find(what) != std::string::npos);
    CHECK(r.err.find(advice) != std::string::npos);
    CHECK(r.err.find("--max-memory") != std::string::npos);
    CHECK(r.out.empty());
  }
  CHECK(!fs::exists(temp("many.rays")));
  CHECK(!fs::exists(temp("h.hits")));
  // Within the budget the same commands run.
  CHECK(run("rays --scene builtin:cornell --count 1000 --max-memory 1 --out " + temp("few.rays").string()).status == 0);
  CHECK(run("trace --scene builtin:cornell --structure bvh --max-memory 20 --rays " + rays.string() + " --hits " +
            temp("h.hits").string()).status == 0);
}

TEST_CASE("the flag --threads limits a run's threads and its reports name the count", "[cli]") {
  const int cpus = tbb::info::default_concurrency();
  for (int threads : {1, 0}) {
    const Run r = run("bench --scene builtin:cornell --count 500 --repeat 1 --structures bvh --json --threads " +
                      std::to_string(threads));
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(nlohmann::json::parse(r.out)["threads"].get<int>() == (threads == 0 ? cpus : threads));
  }
  const Run text = run("bench --scene builtin:cornell --count 500 --repeat 1 --structures bvh --threads 1");
  CHECK(text.out.find("500 rays (closest hit), 1 thread, median") != std::string::npos);
  const Run render = run("render --scene builtin:cornell --size 8x8 --spp 1 --bounces 1 --quiet --threads 1 --out " +
                         temp("threads").string());
  INFO(render.err);
  REQUIRE(render.status == 0);
  std::ifstream report(temp("threads") / "report.json");
  CHECK(nlohmann::json::parse(report)["threads"].get<int>() == 1);
}

TEST_CASE("2l-ls:auto: a plan without a uniform reference has none in its JSON, and a pilot that sees nothing says so", "[cli]") {
  // Just above cornell's fixed part (0.2736 MB): no uniform 2l-ls:D:N fits, so there is none to name.
  const Run r = run("build --scene builtin:cornell --structure 2l-ls:auto --ls-budget 0.274 --json");
  INFO(r.err);
  REQUIRE(r.status == 0);
  const auto plan = nlohmann::json::parse(r.out)["ls_plan"];
  CHECK(plan["reference"].is_null());  // it was "", with a uniform of 0 bytes
  CHECK(plan["uniform"].is_null());
  // A camera that looks away from the scene: the pilot's diffuse rays are the ones that fail.
  write_text(temp("away.gltf"), ls_test::one_triangle_gltf(
                                    R"("nodes":[{"mesh":0},{"camera":0,"translation":[0,0,-5]}],)"
                                    R"("cameras":[{"type":"perspective","perspective":{"yfov":0.5,"znear":0.1}}],)"
                                    R"("scenes":[{"nodes":[0,1]}])"));
  const Run away = run("build --scene " + temp("away.gltf").string() + " --structure 2l-ls:auto --ls-budget 1");
  INFO(away.err);
  CHECK(away.status == 2);
  CHECK(away.err.find("2l-ls:auto's pilot (diffuse rays from the camera's view") != std::string::npos);
}

TEST_CASE("bench measures a structure named twice once", "[cli]") {
  const Run r = run("bench --scene builtin:cornell --count 500 --repeat 1 --structures bvh,f-bvh,f-ls:3:3,bvh --json");
  REQUIRE(r.status == 0);
  const auto results = nlohmann::json::parse(r.out)["results"];
  REQUIRE(results.size() == 3);  // bvh, f-ls:3:3, embree
  CHECK(results[0]["structure"] == "bvh");
  CHECK(results[1]["structure"] == "f-ls:3:3");
}

TEST_CASE("bench --embree-isa limits Embree's instruction set, and refuses a name Embree does not know", "[cli]") {
  const Run r = run("bench --scene builtin:cornell --count 2000 --repeat 1 --structures bvh --embree-isa sse2");
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.find("Embree: sse2") != std::string::npos);
  const Run bad = run("bench --scene builtin:cornell --count 2000 --repeat 1 --structures bvh --embree-isa sse5");
  CHECK(bad.status == 2);
  CHECK(bad.err.find("--embree-isa") != std::string::npos);
  CHECK(bad.out.empty());
}

TEST_CASE("trace refuses a hit file that is its ray file or its --against file, and leaves it as it was", "[cli]") {
  fs::create_directories(temp(""));
  const fs::path rays = temp("self.rays"), hits = temp("self.hits");
  REQUIRE(run("rays --count 10 --out " + rays.string()).status == 0);
  REQUIRE(run("trace --rays " + rays.string() + " --hits " + hits.string()).status == 0);
  const std::string ray_bytes = slurp(rays), hit_bytes = slurp(hits);
  for (const auto& [args, file, bytes] :
       {std::tuple{"--hits " + rays.string(), rays, ray_bytes},
        std::tuple{"--hits " + hits.string() + " --against " + hits.string(), hits, hit_bytes},
        std::tuple{"--hits " + (rays.parent_path() / "." / rays.filename()).string(), rays, ray_bytes}}) {
    const Run r = run("trace --rays " + rays.string() + " " + args);
    INFO(args << ": " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find("is the input file") != std::string::npos);
    CHECK(slurp(file) == bytes);
  }
}

TEST_CASE("a ray with a subnormal direction component is refused, not missed", "[cli]") {
  // One triangle at scale 1 and the line x = 1, z = 1 - s, y = -0.01 + 0.05 s, which crosses it at s = 1.
  // Scaled by 2^-126 the direction's y is subnormal; the box test took it as 0, a ray parallel to the
  // y slab outside it, and missed with exit 0.  At 2^-100 every component is normal and it hits.
  const fs::path obj = temp("subnormal_dir.obj"), rays = temp("subnormal_dir.rays"), hits = temp("subnormal_dir.hits");
  fs::create_directories(obj.parent_path());
  write_text(obj, "v 0 0 0\nv 4 0 0\nv 0 4 0\nf 1 2 3\n");
  auto ray = [](int exponent) {
    return lsk::Ray{glm::vec3(1.0f, -0.01f, 1.0f), 0.0f, glm::vec3(0.0f, std::ldexp(0.05f, exponent), std::ldexp(-1.0f, exponent)),
                    std::numeric_limits<float>::infinity()};
  };
  ls::write_rays(rays.string(), {ray(-100)});
  REQUIRE(run("trace --scene " + obj.string() + " --structure bvh --rays " + rays.string() + " --hits " + hits.string()).status == 0);
  const std::vector<lsk::Hit> hit = ls::read_hits(hits.string());
  REQUIRE(hit.size() == 1);
  CHECK(hit[0].triangle == 0);
  CHECK(hit[0].t == std::ldexp(1.0f, 100));
  // The subnormal one, written as raw bytes (write_rays refuses it and writes nothing).
  const lsk::Ray subnormal = ray(-126);
  REQUIRE(std::fpclassify(subnormal.dir.y) == FP_SUBNORMAL);
  fs::remove(rays);
  CHECK_THROWS_WITH(ls::write_rays(rays.string(), {subnormal}), Catch::Contains("subnormal"));
  CHECK(!fs::exists(rays));
  {
    std::ofstream out(rays, std::ios::binary);
    out.write(reinterpret_cast<const char*>(&subnormal), sizeof subnormal);
  }
  for (const char* structure : {"bvh", "f-ls:0:2"}) {
    const Run r = run("trace --scene " + obj.string() + " --structure " + structure + " --rays " + rays.string() + " --hits " +
                      hits.string());
    INFO(r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find("ray 0: direction component y") != std::string::npos);
  }
}

TEST_CASE("bench and linespace-profile --embree refuse rays Embree cannot take, and bench warns where Embree answers otherwise",
          "[cli]") {
  // Embree 3 aborts on a ray with tmin < 0 or a component past 1.844e18 (its assertions).
  const std::array<std::pair<const char*, lsk::Ray>, 3> outside = {{
      {"tmin -10", lsk::Ray{glm::vec3(0.0f, 1.0f, 3.0f), -10.0f, glm::vec3(0.0f, 0.0f, -1.0f), 1e30f}},
      {"origin 3e38", lsk::Ray{glm::vec3(0.0f, 1.0f, 3e38f), 0.0f, glm::vec3(0.0f, 0.0f, -1.0f), 1e30f}},
      {"direction 1e38", lsk::Ray{glm::vec3(0.0f, 1.0f, 3.0f), 0.0f, glm::vec3(0.0f, 0.0f, -1e38f), 1e30f}},
  }};
  for (const auto& [what, ray] : outside) {
    INFO(what);
    const fs::path rays = temp("embree_domain.rays");
    fs::create_directories(rays.parent_path());
    ls::write_rays(rays.string(), {ray});
    const Run bench = run("bench --scene builtin:cornell --structures bvh --repeat 1 --rays " + rays.string());
    INFO(bench.err);
    CHECK(bench.status == 2);
    CHECK(line_count(bench.err) == 1);
    CHECK(bench.err.find("Embree 3 takes rays with 0 <= tmin") != std::string::npos);
    const Run profile = run_program(LINESPACE_PROFILE, "builtin:cornell bvh " + rays.string() + " --embree", "cli_test");
    INFO(profile.err);
    CHECK(profile.status == 2);
    CHECK(profile.err.find("Embree 3 takes rays with 0 <= tmin") != std::string::npos);
  }
  // One triangle 1e-20 across: Embree misses about half of the random rays that hit it (its
  // kernels' tolerances); at scale 1 the two agree.
  for (const float scale : {1.0f, 1e-20f}) {
    INFO("scale " << scale);
    const fs::path obj = temp("one_triangle.obj");
    char text[128];
    std::snprintf(text, sizeof text, "v 0 0 0\nv %g 0 0\nv 0 %g 0\nf 1 2 3\n", double(scale), double(scale));
    write_text(obj, text);
    const std::string args = "bench --scene " + obj.string() + " --structures bvh --kind random --count 2000 --repeat 1";
    const Run json = run(args + " --json");
    INFO(json.err);
    REQUIRE(json.status == 0);
    const auto j = nlohmann::json::parse(json.out);
    CHECK(j["embree_compared_with"] == "bvh");
    const Run table = run(args);
    if (scale == 1.0f) {
      CHECK(j["embree_disagreement"].get<double>() == 0.0);
      CHECK(table.out.find("warning: Embree's hits differ") == std::string::npos);
    } else {
      CHECK(j["embree_disagreement"].get<double>() > 0.2);
      CHECK(table.out.find("warning: Embree's hits differ from bvh's") != std::string::npos);
    }
  }
  // Without an exact structure there is nothing to compare with: null.
  const Run ls = run("bench --scene builtin:cornell --structures f-ls:3:3 --count 500 --repeat 1 --json");
  REQUIRE(ls.status == 0);
  CHECK(nlohmann::json::parse(ls.out)["embree_disagreement"].is_null());
}

// A schedule's entries past --bounces trace nothing: they are not built, so no budget refuses them
// (f-ls:8:10 takes more than 50 MB on cornell; bounce 0 traces with bvh alone).
TEST_CASE("render builds only what bounces 0..B trace", "[cli]") {
  const fs::path out = temp("render_b0");
  const Run r = run("render --scene builtin:cornell --bounces 0 --schedule bvh,f-ls:8:10 --max-memory 50 --size 8x8 --spp 1 "
                    "--quiet --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  const auto report = nlohmann::json::parse(slurp(out / "report.json"));
  REQUIRE(report["structures"].size() == 1);
  CHECK(report["structures"][0]["structure"] == "bvh");
  const Run used = run("render --scene builtin:cornell --bounces 1 --schedule bvh,f-ls:8:10 --max-memory 50 --size 8x8 "
                       "--spp 1 --quiet --out " + out.string());
  CHECK(used.status == 2);  // the same entry, traced from bounce 1, is over the budget: the check can fail
}

TEST_CASE("an output path that is a directory exits 2 naming it, and leaves no temporary file", "[cli]") {
  const fs::path dir = temp("outputs");
  fs::remove_all(dir);
  fs::create_directories(dir / "hits_here");
  fs::create_directories(dir / "render" / "total.exr");
  REQUIRE(run("rays --scene builtin:cornell --count 100 --out " + (dir / "r.rays").string()).status == 0);
  for (const auto& [args, path] : std::array<std::pair<std::string, fs::path>, 3>{{
           {"trace --scene builtin:cornell --structure bvh --rays " + (dir / "r.rays").string() + " --hits " +
                (dir / "hits_here").string(), dir / "hits_here"},
           {"rays --scene builtin:cornell --count 10 --out " + (dir / "hits_here").string(), dir / "hits_here"},
           {"render --scene builtin:cornell --size 8x8 --spp 1 --quiet --out " + (dir / "render").string(),
            dir / "render" / "total.exr"},
       }}) {
    const Run r = run(args);
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find("cannot write '" + path.string() + "': it is a directory") != std::string::npos);
    for (const auto& entry : fs::recursive_directory_iterator(dir))
      CHECK(entry.path().string().find(".partial") == std::string::npos);
  }
}

TEST_CASE("render writes every image and a report", "[cli]") {
  const fs::path out = temp("render");
  fs::remove_all(out);
  const Run r = run("render --scene builtin:cornell --schedule bvh,2l-bvh --spp 1 --bounces 2 --size 16x12 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  for (const char* f : {"total.exr", "bounce_0.exr", "bounce_1.exr", "bounce_2.exr", "image.png", "report.json"})
    CHECK(fs::exists(out / f));
  std::ifstream f(out / "report.json");
  const auto j = nlohmann::json::parse(f);
  CHECK(j["per_bounce"].size() == 3);
  CHECK(j["per_bounce"][0]["structure"] == "bvh");
  CHECK(j["per_bounce"][2]["structure"] == "2l-bvh");
  CHECK(j["per_bounce"][0]["extension_rays"].get<int>() == 16 * 12);
  CHECK(j["indirect"]["rays"].get<long>() > 0);
  CHECK(j.contains("primary"));
  CHECK(j["dropped_samples"].get<long>() == 0);  // non-finite contributions left out, always reported
}

// The bound includes process start and loading builtin:instances (~0.3 s of CPU; seconds of wall time on a
// loaded machine or under ASan): an attempted build would take hours or be killed for memory.
TEST_CASE("over-budget structures and renders exit 2 within seconds naming estimate, budget and flag", "[cli]") {
  // 4000 MB = 3814.7 MiB, 16 MB = 15.3 MiB, 5 MB = 4.77 MiB: budgets are named rounded down, in
  // tenths below 10 MiB.  The fourth: the BVH's estimate fits 5 MB, the structure and its fast
  // path's bound do not (memory_budget.h).
  const std::array<std::tuple<std::string, std::string, std::string>, 5> cases = {{
      {"build --scene builtin:instances --structure f-ls:8:64 --max-memory 4000", "budget of 3814 MiB", "lower N or D"},
      {"build --scene builtin:instances --structure f-ls:30:10 --max-memory 4000", "budget of 3814 MiB", "lower N or D"},
      {"build --scene builtin:instances --structure bvh --max-memory 16", "budget of 15 MiB", "smaller scene"},
      {"build --scene builtin:generated:20000:7:3 --structure bvh --max-memory 5", "budget of 4.7 MiB", "the fast path of"},
      {"render --scene builtin:cornell --size 16384x16384 --bounces 64 --max-memory 4000 --out " + temp("big").string(),
       "budget of 3814 MiB", "--size"},
  }};
  for (const auto& [args, budget, advice] : cases) {
    const auto start = std::chrono::steady_clock::now();
    const Run r = run(args);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find("MiB") != std::string::npos);
    CHECK(r.err.find(budget) != std::string::npos);
    CHECK(r.err.find(advice) != std::string::npos);
    CHECK(r.err.find("--max-memory") != std::string::npos);
    CHECK(seconds < 10.0);
  }
  CHECK(!fs::exists(temp("big")));
}

TEST_CASE("SIGINT during render and SIGTERM during a build exit 128+signal leaving no output file", "[cli]") {
  fs::create_directories(temp(""));
  const fs::path out = temp("interrupted_render"), err = temp("interrupt.err");
  fs::remove_all(out);
  // Far longer than the delay: the signal arrives mid-render.
  int status = run_and_signal(LINESPACE_CPU,
                              {"render", "--scene", "builtin:cornell", "--size", "256x256", "--spp", "65536", "--out", out.string()},
                              err.string(), SIGINT, 1.5);
  INFO("stderr: " << slurp(err));
  CHECK(status == 130);
  CHECK(slurp(err).find("interrupted by SIGINT") != std::string::npos);
  CHECK((!fs::exists(out) || fs::is_empty(out)));

  status = run_and_signal(LINESPACE_CPU, {"build", "--scene", "builtin:instances", "--structure", "f-ls:6:14"}, err.string(),
                          SIGTERM, 1.5);
  INFO("stderr: " << slurp(err));
  CHECK(status == 143);
  CHECK(slurp(err).find("interrupted by SIGTERM") != std::string::npos);
}

TEST_CASE("hostile scenes through linespace-cpu: exit 2 with one line, or a finite render", "[cli]") {
  using namespace ls_test;
  fs::create_directories(temp(""));
  const auto triangles = [](const std::string& material, const std::string& nodes) {
    Gltf g;
    const int pos = g.vec3({{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, -1, 0}, {1, 1, 0}, {-1, 1, 0}});
    return g.json(R"("materials":[)" + material + R"(],"meshes":[{"primitives":[{"attributes":{"POSITION":)" +
                  std::to_string(pos) + R"(},"material":0}]}],)" + nodes);
  };
  const std::string one_node = R"("nodes":[{"mesh":0}])";
  {
    Gltf g;
    g.vec3(kTriangle);  // view 0, accessor 0; accessor 1 reads the same bytes as unsigned shorts
    g.accessor(R"({"bufferView":0,"componentType":5123,"count":3,"type":"VEC3"})");
    write_text(temp("shorts.glb"), g.glb(R"("meshes":[{"primitives":[{"attributes":{"POSITION":1}}]}],"nodes":[{"mesh":0}])"));
  }
  write_text(temp("strength.gltf"), triangles(R"({"emissiveFactor":[10,10,10],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":1e38}}})", one_node));
  write_text(temp("cycle.gltf"), triangles("{}", R"("nodes":[{"mesh":0,"children":[1]},{"children":[0]}],"scenes":[{"nodes":[0]}])"));
  write_text(temp("mirror_singular.gltf"), triangles("{}", R"("nodes":[{"mesh":0,"scale":[-1,0,1]}])"));
  for (const char* name : {"shorts.glb", "strength.gltf", "cycle.gltf", "mirror_singular.gltf"}) {
    const Run r = run("render --size 8x8 --spp 1 --scene " + temp(name).string() + " --out " + temp("hostile_out").string());
    INFO(name << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.find(temp(name).string()) != std::string::npos);
  }
  CHECK(!fs::exists(temp("hostile_out")));
  // A mirroring transform and a light of zero power: valid, rendered (black), no sample dropped.
  write_text(temp("mirror_dark.gltf"), triangles(R"({"emissiveFactor":[0,0,0]})", R"("nodes":[{"mesh":0,"scale":[-1,1,1]}])"));
  const Run r = run("render --size 8x8 --spp 1 --scene " + temp("mirror_dark.gltf").string() + " --out " + temp("dark").string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  std::ifstream f(temp("dark") / "report.json");
  CHECK(nlohmann::json::parse(f)["dropped_samples"].get<long>() == 0);
}

namespace {

// An animated glTF for `render --frames`: a static emissive quad lighting a white triangle (node 1)
// that slides along x, LINEAR over 1 s.  extra_channels: more channels on node 1 (sampler 0's keys).
std::string animated_gltf(const std::string& extra_channels = "", const std::string& extra_animations = "") {
  using namespace ls_test;
  Gltf g;
  const int quad = g.vec3({{-2, 2, -1}, {2, 2, -1}, {2, 2, 1}, {-2, 2, -1}, {2, 2, 1}, {-2, 2, 1}});
  const int tri = g.vec3({{-0.5f, 0, -0.5f}, {0.5f, 0, -0.5f}, {0, 0, 0.5f}});
  const int times = g.scalars({0.0f, 1.0f});
  const int moves = g.vec3({{-1, 0, 0}, {1, 0, 0}});
  return g.json(R"("materials":[{"emissiveFactor":[4,4,4]},{}],"meshes":[{"primitives":[{"attributes":{"POSITION":)" +
                std::to_string(quad) + R"(},"material":0}]},{"primitives":[{"attributes":{"POSITION":)" + std::to_string(tri) +
                R"(},"material":1}]}],"nodes":[{"mesh":0},{"mesh":1},{"camera":0,"translation":[0,1,4]}],)"
                R"("cameras":[{"type":"perspective","perspective":{"yfov":1.0,"znear":0.1}}],)"
                R"("animations":[{"name":"slide","channels":[)" + channel_json(0, 1, "translation") + extra_channels +
                R"(],"samplers":[)" + sampler_json(times, moves, "LINEAR") + "]}" + extra_animations + "]");
}

}  // namespace

TEST_CASE("render --frames writes one folder per frame and frames.json with the documented keys", "[cli][animation]") {
  using nlohmann::json;
  fs::create_directories(temp(""));
  write_text(temp("slide.gltf"), animated_gltf());
  const fs::path out = temp("frames");
  fs::remove_all(out);
  // --bounces 2: every entry of the schedule is traced (one past the last bounce would not be built).
  const Run r = run("render --scene " + temp("slide.gltf").string() + " --schedule bvh,2l-bvh,2l-ls:1:2 --spp 1 --bounces 2 " +
                    "--size 24x16 --frames 2:4 --fps 4 --out " + out.string());
  INFO(r.out << r.err);
  REQUIRE(r.status == 0);
  std::vector<std::string> pngs;
  for (int f = 2; f <= 4; ++f) {
    const fs::path dir = out / ("frame_000" + std::to_string(f));
    for (const char* file : {"total.exr", "bounce_0.exr", "bounce_1.exr", "bounce_2.exr", "image.png", "report.json"})
      CHECK(fs::exists(dir / file));
    std::ifstream rf(dir / "report.json");
    const json report = json::parse(rf);
    CHECK(report["frame"]["frame"] == f);
    CHECK(report["per_bounce"].size() == 3);
    pngs.push_back(slurp(dir / "image.png"));
  }
  CHECK(pngs[0] != pngs[1]);  // the triangle moved
  CHECK(pngs[1] != pngs[2]);
  for (const auto& entry : fs::recursive_directory_iterator(out)) CHECK(entry.path().string().find(".partial") == std::string::npos);

  std::ifstream f(out / "frames.json");
  const json j = json::parse(f);
  for (const char* key : {"scene", "animation", "schedule", "width", "height", "spp", "bounces", "seed", "fps", "first_frame",
                          "last_frame", "top_level_update", "flat_comparison", "device", "threads", "initial_build", "frames",
                          "frames_done", "complete", "summary"})
    CHECK(j.contains(key));
  CHECK(j["animation"]["name"] == "slide");
  CHECK(j["animation"]["duration"] == 1.0);
  CHECK(j["complete"] == true);
  CHECK(j["frames_done"] == 3);
  CHECK(j["top_level_update"] == "rebuild");
  CHECK(j["initial_build"].size() == 2);  // 2l-bvh and 2l-ls:1:2, once
  REQUIRE(j["frames"].size() == 3);
  for (size_t i = 0; i < 3; ++i) {
    const json& fr = j["frames"][i];
    CHECK(fr["frame"] == int(i) + 2);
    CHECK(fr["time"].get<double>() == (double(i) + 2.0) / 4.0);
    CHECK(fr["dir"] == "frame_000" + std::to_string(i + 2));
    for (const char* key : {"render_seconds", "indirect_rays", "indirect_seconds", "indirect_mrays_per_s"}) CHECK(fr.contains(key));
    REQUIRE(fr["updates"].size() == 3);
    CHECK(fr["updates"][0]["structure"] == "bvh");
    CHECK(fr["updates"][0]["update"] == "rebuild");
    CHECK_FALSE(fr["updates"][0].contains("flat_structure"));
    CHECK(fr["updates"][1]["update"] == "top-level");
    CHECK(fr["updates"][1]["flat_structure"] == "bvh");
    // 2l-bvh's comparison is the schedule's own bvh rebuild of this frame
    CHECK(fr["updates"][1]["flat_rebuild_seconds"] == fr["updates"][0]["seconds"]);
    CHECK(fr["updates"][2]["flat_structure"] == "f-ls:1:2");
    for (const json& u : fr["updates"]) CHECK(u["seconds"].get<double>() > 0.0);
    CHECK(fr["updates"][2]["flat_rebuild_seconds"].get<double>() > 0.0);
    CHECK(fr["updates"][2].contains("flat_over_update"));
  }
  REQUIRE(j["summary"].size() == 3);
  CHECK(j["summary"][2]["flat_structure"] == "f-ls:1:2");
  CHECK(j["summary"][2].contains("median_flat_rebuild_seconds"));
  // A line per frame on stderr, a header and a row per frame on stdout.
  CHECK(line_count(r.err) == 3);
  CHECK(r.out.find("2l-ls:1:2 top ms") != std::string::npos);
  CHECK(r.out.find("median per frame: 2l-ls:1:2 top-level") != std::string::npos);

  // --no-flat-comparison and a refitted top level; a still render of the animated file notes it.
  const Run q = run("render --scene " + temp("slide.gltf").string() + " --schedule 2l-ls:1:2 --spp 1 --bounces 0 --size 8x8 " +
                    "--frames 0:1 --no-flat-comparison --top-level-update refit --quiet --out " + temp("frames_q").string());
  INFO(q.err);
  REQUIRE(q.status == 0);
  CHECK(q.err.empty());
  std::ifstream fq(temp("frames_q") / "frames.json");
  const json jq = json::parse(fq);
  CHECK(jq["top_level_update"] == "refit");
  CHECK_FALSE(jq["frames"][0]["updates"][0].contains("flat_structure"));
  const Run still = run("render --scene " + temp("slide.gltf").string() + " --spp 1 --size 8x8 --quiet --out " + temp("still").string());
  CHECK(still.status == 0);
  CHECK(still.err.find("note: ") == 0);
}

TEST_CASE("render --frames on a scene without animation renders the same pose with a note", "[cli][animation]") {
  const fs::path out = temp("static_frames");
  fs::remove_all(out);
  const Run r = run("render --scene builtin:cornell --schedule 2l-bvh --spp 1 --bounces 1 --size 16x16 --frames 0:1 --quiet "
                    "--no-flat-comparison --out " + out.string());
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.find("has no animation") != std::string::npos);
  CHECK(slurp(out / "frame_0000" / "image.png") == slurp(out / "frame_0001" / "image.png"));
}

TEST_CASE("render --frames: bad ranges, rates and animations exit 2 with a one-line reason", "[cli][animation]") {
  using namespace ls_test;
  fs::create_directories(temp(""));
  write_text(temp("slide2.gltf"), animated_gltf());
  {
    Gltf g;  // a weights channel: not rigid
    const int pos = g.vec3(kTriangle), times = g.scalars({0.0f, 1.0f}), w = g.scalars({0.0f, 1.0f});
    write_text(temp("weights.gltf"), g.json(R"("materials":[{"emissiveFactor":[1,1,1]}],"meshes":[{"primitives":[{"attributes":{"POSITION":)" +
                                                std::to_string(pos) + R"(},"material":0}]}],"nodes":[{"mesh":0}],"animations":[{"channels":[)" +
                                                channel_json(0, 0, "weights") + R"(],"samplers":[)" + sampler_json(times, w, "LINEAR") + "]}]"));
  }
  {
    Gltf g;  // a scale key of 0 at 1 s: the pose of frame 24 is singular
    const int pos = g.vec3(kTriangle), times = g.scalars({0.0f, 1.0f}), s = g.vec3({{1, 1, 1}, {0, 1, 1}});
    write_text(temp("flatten.gltf"), g.json(R"("materials":[{"emissiveFactor":[1,1,1]}],"meshes":[{"primitives":[{"attributes":{"POSITION":)" +
                                                std::to_string(pos) + R"(},"material":0}]}],"nodes":[{"mesh":0}],"animations":[{"channels":[)" +
                                                channel_json(0, 0, "scale") + R"(],"samplers":[)" + sampler_json(times, s, "STEP") + "]}]"));
  }
  const std::string scene = " --scene " + temp("slide2.gltf").string() + " --size 8x8 --spp 1 --out " + temp("bad_frames").string();
  const std::vector<std::string> cases = {
      "render --frames 5:2" + scene,
      "render --frames -1:3" + scene,
      "render --frames a:b" + scene,
      "render --frames 1:2:3" + scene,
      "render --frames 0:10000" + scene,
      "render --frames 99999999" + scene,
      "render --frames 0:1 --fps 0" + scene,
      "render --frames 0:1 --fps 1e9" + scene,
      "render --fps 30" + scene,
      "render --frames 0:1 --animation 1" + scene,
      "render --frames 0:1 --top-level-update sideways" + scene,
      "render --frames 0:1 --scene " + temp("weights.gltf").string() + " --size 8x8 --out " + temp("bad_frames").string(),
      "render --frames 0:30 --scene " + temp("flatten.gltf").string() + " --size 8x8 --out " + temp("bad_frames").string(),
      "render --frames 0:1 --animation 2 --scene builtin:cornell --size 8x8 --out " + temp("bad_frames").string(),
  };
  for (const std::string& args : cases) {
    const Run r = run(args);
    INFO(args << "\nstderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(line_count(r.err) == 1);
    CHECK(r.err.rfind("linespace-cpu: ", 0) == 0);
  }
  CHECK(!fs::exists(temp("bad_frames")));
}

TEST_CASE("SIGINT during render --frames exits 130 leaving only whole frames and a frames.json that lists them", "[cli][animation]") {
  fs::create_directories(temp(""));
  const fs::path out = temp("interrupted_frames"), err = temp("frames_interrupt.err");
  fs::remove_all(out);
  const int status = run_and_signal(LINESPACE_CPU,
                                    {"render", "--scene", "builtin:cornell", "--schedule", "2l-bvh", "--size", "64x64", "--spp",
                                     "512", "--bounces", "1", "--frames", "0:1000", "--no-flat-comparison", "--out", out.string()},
                                    err.string(), SIGINT, 2.0);
  INFO("stderr: " << slurp(err));
  CHECK(status == 130);
  size_t frames = 0;
  if (fs::exists(out))
    for (const auto& entry : fs::recursive_directory_iterator(out)) {
      CHECK(entry.path().string().find(".partial") == std::string::npos);
      if (entry.is_directory()) {
        ++frames;
        CHECK(fs::exists(entry.path() / "report.json"));
      }
    }
  if (frames > 0) {
    std::ifstream f(out / "frames.json");
    const auto j = nlohmann::json::parse(f);
    CHECK(j["complete"] == false);
    CHECK(j["frames_done"].get<size_t>() == frames);
  }
}
