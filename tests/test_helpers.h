// Shared test code (tests/README.md, "Shared helpers"): the program runner, and the random numbers,
// rays, meshes, triangle soups and scenes the tests build from.
//
// The factories are deterministic, and several tests compare against brute force with fixed seeds or
// assert counts, so each one must keep producing exactly the data it did: where two tests generate in
// different ways (another random source, another distribution, other normals), they are separate
// functions here, named for what they make, not one function that would change either's data.
#pragma once

#include "common/kernels/layouts.h"
#include "common/model/scene.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <system_error>
#include <utility>
#include <vector>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

namespace test_support {

// ---------------------------------------------------------------------------------------------------
// Running our programs as a user would.  Each test process works in its own folder: ctest runs test
// cases in parallel.

struct Run {
  int status = -1;
  std::string out, err;
};

// TMPDIR/linespace_<tag>_<pid>/<name>.
inline std::filesystem::path temp_path(const std::string& tag, const std::string& name) {
  return std::filesystem::temp_directory_path() / ("linespace_" + tag + "_" + std::to_string(getpid())) / name;
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Runs `program args` through the shell, with `env` (assignments such as "A=1 B=2") in front when
// given, capturing its exit status (-1: killed by a signal), stdout and stderr.
inline Run run_program(const std::string& program, const std::string& args, const std::string& tag,
                       const std::string& env = "") {
  std::filesystem::create_directories(temp_path(tag, ""));
  const std::string out = temp_path(tag, "stdout").string(), err = temp_path(tag, "stderr").string();
  const std::string prefix = env.empty() ? "" : env + " ";
  const int raw = std::system((prefix + program + " " + args + " >" + out + " 2>" + err).c_str());
  Run r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// Whether process `pid` runs `program` (not a forked test still before exec, which carries Catch's
// handlers) and has a handler for `signal` (the SigCgt mask of /proc/PID/status).
inline bool catches_signal(pid_t pid, const std::string& program, int signal) {
  std::error_code ec;
  if (std::filesystem::read_symlink("/proc/" + std::to_string(pid) + "/exe", ec) != std::filesystem::canonical(program, ec))
    return false;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (signal - 1)) & 1u;
  return false;
}

// Starts `program` with `args` (stderr to err_path, stdout to /dev/null), sends `signal` once it has
// run `delay` seconds with its handlers installed, and returns its exit status (-1: killed by a signal
// or still running 60 s later).
inline int run_and_signal(const std::string& program, const std::vector<std::string>& args, const std::string& err_path,
                          int signal, double delay) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv{const_cast<char*>(program.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (!std::freopen(err_path.c_str(), "w", stderr) || !std::freopen("/dev/null", "w", stdout)) _exit(99);
    execv(program.c_str(), argv.data());
    _exit(98);
  }
  // Wait until the program has installed its handler (SigCgt in /proc), however slowly it starts,
  // then give it `delay` seconds of work before the signal.
  for (int waited = 0; waited < 300 && !catches_signal(pid, program, signal); ++waited) usleep(100000);
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

// ---------------------------------------------------------------------------------------------------
// Random numbers.  Two sources, both std::mt19937 with fixed seeds; the tests that use each depend on
// its exact sequence, so neither stands in for the other.

// Floats from the top 24 bits of a 32-bit draw: the same numbers with every standard library.
struct Rng {
  std::mt19937 gen;
  explicit Rng(uint32_t seed) : gen(seed) {}
  float uniform() { return float(gen() >> 8) * 0x1.0p-24f; }  // [0, 1)
  float range(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  glm::vec3 vec(float lo, float hi) { return glm::vec3(range(lo, hi), range(lo, hi), range(lo, hi)); }
  glm::vec3 unit() {  // uniform on the sphere
    const float z = 1.0f - 2.0f * uniform();
    const float phi = 6.28318530718f * uniform();
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    return glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
  }
};

// Numbers from the standard distributions (std::uniform_int_distribution, std::uniform_real_distribution).
struct StdRng {
  std::mt19937 gen;
  explicit StdRng(uint32_t seed) : gen(seed) {}
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(gen); }
  float range(float a, float b) { return std::uniform_real_distribution<float>(a, b)(gen); }
  glm::vec3 vec(float a, float b) { return glm::vec3(range(a, b), range(a, b), range(a, b)); }
  // A point of the 1/step grid in [-extent, extent]^3.
  glm::vec3 grid(float extent, int step) {
    const int n = int(extent * float(step));
    return glm::vec3(float(integer(-n, n)), float(integer(-n, n)), float(integer(-n, n))) / float(step);
  }
};

// ---------------------------------------------------------------------------------------------------
// Rays.

inline lsk::Ray make_ray(const glm::vec3& o, const glm::vec3& d, float tmin = 0.0f,
                         float tmax = std::numeric_limits<float>::infinity()) {
  lsk::Ray r;
  r.origin = o;
  r.dir = d;
  r.tmin = tmin;
  r.tmax = tmax;
  return r;
}

// ---------------------------------------------------------------------------------------------------
// Meshes.

// A complete mesh: every normal (0, 0, 1), every triangle material 0.
inline ls::Mesh make_mesh(std::vector<glm::vec3> positions, std::vector<glm::uvec3> triangles, const std::string& name = "") {
  ls::Mesh m;
  m.name = name;
  m.positions = std::move(positions);
  m.triangles = std::move(triangles);
  m.normals.assign(m.positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  m.materials.assign(m.triangles.size(), 0u);
  return m;
}

// Face normals as vertex normals (the Line Space extrapolates them), in triangle order (a vertex shared
// by several triangles keeps the last one's); vertices only in zero-area triangles keep (0, 0, 1).
inline ls::Mesh with_face_normals(ls::Mesh m) {
  m.normals.assign(m.positions.size(), glm::vec3(0.0f, 0.0f, 1.0f));
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const glm::uvec3 i = m.triangles[t];
    const glm::vec3 n = glm::cross(m.positions[i.y] - m.positions[i.x], m.positions[i.z] - m.positions[i.x]);
    if (glm::length(n) > 0.0f) m.normals[i.x] = m.normals[i.y] = m.normals[i.z] = glm::normalize(n);
  }
  return m;
}

// Radial normals (p / |p|, (0, 1, 0) at the origin: the loaders guarantee one per position, and these
// are enough for tests) and material 0 on every triangle.
inline void finish_with_radial_normals(ls::Mesh& mesh) {
  mesh.normals.clear();
  for (const glm::vec3& p : mesh.positions) {
    const float len = glm::length(p);
    mesh.normals.push_back(len > 0.0f ? p / len : glm::vec3(0.0f, 1.0f, 0.0f));
  }
  mesh.materials.assign(mesh.triangles.size(), 0u);
}

// A closed UV sphere: no concave edges, so light samples on a neighbouring facet never sit in a
// corner (where a light sample's variance is unbounded), and a ray that leaves a facet outwards
// meets nothing.
inline ls::Mesh closed_sphere(float radius, int rings, int segments) {
  ls::Mesh m;
  m.name = "sphere";
  for (int r = 0; r <= rings; ++r)
    for (int g = 0; g < segments; ++g) {
      const float th = float(M_PI) * float(r) / float(rings), ph = 2.0f * float(M_PI) * float(g) / float(segments);
      m.positions.push_back(radius * glm::vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)));
    }
  for (int r = 0; r < rings; ++r)
    for (int g = 0; g < segments; ++g) {
      const uint32_t a = uint32_t(r * segments + g), b = uint32_t(r * segments + (g + 1) % segments);
      const uint32_t c = a + uint32_t(segments), d = b + uint32_t(segments);
      if (r > 0) m.triangles.push_back(glm::uvec3(a, b, d));
      if (r < rings - 1) m.triangles.push_back(glm::uvec3(a, d, c));
    }
  m.materials.assign(m.triangles.size(), 0);
  for (const glm::vec3& p : m.positions) m.normals.push_back(glm::normalize(p));
  return m;
}

// The square [lo, hi]^2 in the z = 0 plane as a grid of cells x cells quads, two triangles each
// sharing the quad's diagonal (and the grid its vertices); normals (0, 0, 1).
inline ls::Mesh square_grid(int cells, float lo = -1.0f, float hi = 1.0f, const std::string& name = "") {
  std::vector<glm::vec3> p;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      p.push_back(glm::vec3(lo + (hi - lo) * float(i) / float(cells), lo + (hi - lo) * float(j) / float(cells), 0.0f));
  const auto at = [&](int i, int j) { return uint32_t(j * (cells + 1) + i); };
  std::vector<glm::uvec3> t;
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      t.push_back(glm::uvec3(at(i, j), at(i + 1, j), at(i + 1, j + 1)));
      t.push_back(glm::uvec3(at(i, j), at(i + 1, j + 1), at(i, j + 1)));
    }
  return make_mesh(std::move(p), std::move(t), name);
}

// ---------------------------------------------------------------------------------------------------
// Triangle soups: unconnected triangles, three vertices each, in draw order.

// n triangles, each with its centre drawn in [-extent, extent]^3 and then its three vertices each
// drawn in the centre's [-size, size]^3; normals (0, 0, 1).  The data depend on the source: Rng
// (random_soup) or StdRng.
template <class Source>
ls::Mesh scattered_soup(Source& rng, size_t n, float extent, float size, const std::string& name = "") {
  std::vector<glm::vec3> p;
  std::vector<glm::uvec3> t;
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 c = rng.vec(-extent, extent);
    for (int k = 0; k < 3; ++k) p.push_back(c + rng.vec(-size, size));
    t.push_back(glm::uvec3(3 * i, 3 * i + 1, 3 * i + 2));
  }
  return make_mesh(std::move(p), std::move(t), name);
}

// scattered_soup from Rng(seed).
inline ls::Mesh random_soup(size_t n, uint32_t seed, float extent = 1.0f, float size = 0.15f, const std::string& name = "") {
  Rng rng(seed);
  return scattered_soup(rng, n, extent, size, name);
}

// Small triangles clustered in the unit cube [0, 1]^3: each centre drawn there, its vertices at
// centre + size * [-0.5, 0.5)^3 (Rng(seed)); each triangle's face normal on its three vertices.
inline ls::Mesh unit_cube_soup(int count, uint32_t seed, float size = 0.08f) {
  Rng rng(seed);
  ls::Mesh m;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 c(rng.uniform(), rng.uniform(), rng.uniform());
    glm::vec3 p[3];
    for (auto& q : p) q = c + size * glm::vec3(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    const glm::vec3 n = glm::normalize(glm::cross(p[1] - p[0], p[2] - p[0]));
    for (auto& q : p) {
      m.positions.push_back(q);
      m.normals.push_back(n);
    }
    m.triangles.push_back(glm::uvec3(3 * i, 3 * i + 1, 3 * i + 2));
  }
  m.materials.assign(m.triangles.size(), 0u);
  return m;
}

// n triangles with every vertex on the 1/16 grid (StdRng(seed)): each centre in [-0.8, 0.8]^3 and its
// vertices within 0.2 of it, so that they are exact in float, and so are their images under dyadic
// translations, 180-degree turns and power-of-two scales; normals (0, 0, 1).
inline ls::Mesh lattice_soup(int n, uint32_t seed) {
  StdRng rng(seed);
  std::vector<glm::vec3> p;
  std::vector<glm::uvec3> t;
  for (int i = 0; i < n; ++i) {
    const glm::vec3 c = rng.grid(0.8f, 16);
    for (int k = 0; k < 3; ++k) p.push_back(c + rng.grid(0.2f, 16));
    t.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
  }
  return make_mesh(std::move(p), std::move(t));
}

// ---------------------------------------------------------------------------------------------------
// Scenes.

// One mesh placed once per transform, scene "test" with one default material; materials set to 0,
// and normals to (0, 0, 1) where the mesh has not one per position.  Validated.
inline ls::Scene single_mesh_scene(ls::Mesh mesh, const std::vector<glm::mat4>& transforms = {glm::mat4(1.0f)}) {
  ls::Scene s;
  s.name = "test";
  s.materials.push_back(ls::Material{});
  mesh.materials.assign(mesh.triangles.size(), 0);
  if (mesh.normals.size() != mesh.positions.size()) mesh.normals.assign(mesh.positions.size(), glm::vec3(0, 0, 1));
  s.meshes.push_back(std::move(mesh));
  for (const glm::mat4& m : transforms) s.instances.push_back(ls::Instance{0, m, ""});
  ls::validate_scene(s);
  return s;
}

}  // namespace test_support
