// linespace-cpu end to end: the file formats, the JSON keys of DESIGN §9, and exit status 2 with a
// one-line reason on bad input.
#include "gltf_writer.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

struct Run {
  int status = -1;
  std::string out, err;
};

// Each test process gets its own folder: ctest runs test cases in parallel.
fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("linespace_cli_test_" + std::to_string(getpid())) / name;
}

Run run(const std::string& args) {
  fs::create_directories(temp(""));
  const std::string out = temp("stdout").string(), err = temp("stderr").string();
  const std::string cmd = std::string(LINESPACE_CPU) + " " + args + " >" + out + " 2>" + err;
  const int raw = std::system(cmd.c_str());
  Run r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  auto slurp = [](const std::string& p) {
    std::ifstream f(p);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

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
  const std::array<std::string, 21> cases = {
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
  // The cornell room is closed: every diffuse ray hits something, with a finite t and valid ids.
  std::ifstream f(hits, std::ios::binary);
  for (int i = 0; i < 1000; ++i) {
    float t, u, v;
    uint32_t inst, tri;
    f.read(reinterpret_cast<char*>(&t), 4).read(reinterpret_cast<char*>(&inst), 4).read(reinterpret_cast<char*>(&tri), 4);
    f.read(reinterpret_cast<char*>(&u), 4).read(reinterpret_cast<char*>(&v), 4);
    REQUIRE(std::isfinite(t));
    REQUIRE(tri != 0xFFFFFFFFu);
    REQUIRE(u >= 0.0f);
    REQUIRE(v >= 0.0f);
    REQUIRE(u + v <= 1.0001f);
  }
  r = run("build --scene builtin:cornell --structure 2l-bvh --json");
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"triangles", "objects", "instances", "nodes", "ls_nodes", "shafts_per_ls", "bytes_total", "bytes_ls",
                          "build_seconds"})
    CHECK(j.contains(key));
  CHECK(j["triangles"].get<int>() > 0);
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
  // 4000 MB = 3815 MiB (rounded up), 16 MB = 16 MiB.
  const std::array<std::tuple<std::string, std::string, std::string>, 4> cases = {{
      {"build --scene builtin:instances --structure f-ls:8:64 --max-memory 4000", "budget of 3815 MiB", "lower N or D"},
      {"build --scene builtin:instances --structure f-ls:30:10 --max-memory 4000", "budget of 3815 MiB", "lower N or D"},
      {"build --scene builtin:instances --structure bvh --max-memory 16", "budget of 16 MiB", "smaller scene"},
      {"render --scene builtin:cornell --size 16384x16384 --bounces 64 --max-memory 4000 --out " + temp("big").string(),
       "budget of 3815 MiB", "--size"},
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

namespace {

// Whether process `pid` runs linespace-cpu (not the forked test still before exec, which carries
// Catch's handlers) and has a handler for `signal` (the SigCgt mask of /proc/PID/status).
bool catches(pid_t pid, int signal) {
  std::error_code ec;
  if (fs::read_symlink("/proc/" + std::to_string(pid) + "/exe", ec) != fs::canonical(LINESPACE_CPU, ec)) return false;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (signal - 1)) & 1u;
  return false;
}

// Starts linespace-cpu with `args` (stderr to err_path), sends `signal` once it has run `delay` seconds
// with its handlers installed, and returns its exit status (-1: killed by a signal or still running
// 60 s later).
int run_and_signal(const std::vector<std::string>& args, const std::string& err_path, int signal, double delay) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(LINESPACE_CPU)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (!std::freopen(err_path.c_str(), "w", stderr) || !std::freopen("/dev/null", "w", stdout)) _exit(99);
    execv(LINESPACE_CPU, argv.data());
    _exit(98);
  }
  // Wait until the program has installed its handler (SigCgt in /proc), however slowly it starts,
  // then give it `delay` seconds of work before the signal.
  for (int waited = 0; waited < 300 && !catches(pid, signal); ++waited) usleep(100000);
  usleep(useconds_t(delay * 1e6));
  kill(pid, signal);
  int status = 0;
  for (int waited = 0; waited < 600; ++waited) {  // up to 60 s
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    usleep(100000);
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

TEST_CASE("SIGINT during render and SIGTERM during a build exit 128+signal leaving no output file", "[cli]") {
  fs::create_directories(temp(""));
  const fs::path out = temp("interrupted_render"), err = temp("interrupt.err");
  fs::remove_all(out);
  // Far longer than the delay: the signal arrives mid-render.
  int status = run_and_signal({"render", "--scene", "builtin:cornell", "--size", "256x256", "--spp", "65536", "--out",
                               out.string()},
                              err.string(), SIGINT, 1.5);
  INFO("stderr: " << slurp(err));
  CHECK(status == 130);
  CHECK(slurp(err).find("interrupted by SIGINT") != std::string::npos);
  CHECK((!fs::exists(out) || fs::is_empty(out)));

  status = run_and_signal({"build", "--scene", "builtin:instances", "--structure", "f-ls:6:14"}, err.string(), SIGTERM, 1.5);
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
