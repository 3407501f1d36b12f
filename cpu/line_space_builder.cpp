#include "line_space_builder.h"

#include "accel.h"
#include "interrupt.h"
#include "parallel.h"

#include <glm/gtc/packing.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>

namespace ls {
namespace {

// A box whose thin axes are widened to 2^-10 of its largest extent, centred, so that the shafts of a
// flat node (one quad) still cross its triangles.  Zero largest extent: no usable box.
bool ls_box(const lsk::BvhNode& node, glm::vec3& lo, glm::vec3& hi) {
  lo = node.lo;
  hi = node.hi;
  const glm::vec3 ext = hi - lo;
  const float m = std::max({ext.x, ext.y, ext.z});
  if (!(m > 0.0f) || !std::isfinite(m)) return false;
  const float min_thickness = std::ldexp(m, -10);
  for (int a = 0; a < 3; ++a)
    if (ext[a] < min_thickness) {
      const float c = 0.5f * (lo[a] + hi[a]);
      lo[a] = c - 0.5f * min_thickness;
      hi[a] = c + 0.5f * min_thickness;
    }
  return hi.x > lo.x && hi.y > lo.y && hi.z > lo.z;
}

uint32_t candidate_bytes(uint32_t range_count, bool paper) {
  if (paper) return 4;
  if (range_count <= 255) return 1;  // 0..254, 255 = empty
  if (range_count <= 65535) return 2;
  return 4;
}

glm::uvec4 encode_normals(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  auto enc = [](glm::vec3 n) -> uint32_t {
    const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) return glm::packSnorm2x16(glm::vec2(0.0f));  // decodes to +z
    n /= l1;
    glm::vec2 e(n.x, n.y);
    if (n.z < 0.0f)
      e = glm::vec2((1.0f - std::fabs(n.y)) * (n.x >= 0.0f ? 1.0f : -1.0f), (1.0f - std::fabs(n.x)) * (n.y >= 0.0f ? 1.0f : -1.0f));
    return glm::packSnorm2x16(e);
  };
  return glm::uvec4(enc(a), enc(b), enc(c), 0u);
}

struct Range {
  uint32_t first = 0, count = 0;
};

// Octahedral vertex normals per triangle of the structure, in the space of its BVH: world space for
// F-LS (each instance's normal matrix applied), object space for 2L-LS.
void compute_triangle_normals(const Scene& scene, const std::vector<Range>& range, Accel& accel) {
  accel.tri_normals.resize(accel.tris.size());
  if (accel.spec.two_level()) {
    for (size_t m = 0; m < accel.object_roots.size(); ++m) {
      if (accel.object_roots[m] == lsk::LS_INVALID) continue;
      const Mesh& mesh = scene.meshes[m];
      const Range r = range[accel.object_roots[m]];
      ls::parallel_for(r.first, r.first + r.count, [&](uint32_t k) {
        const glm::uvec3 idx = mesh.triangles[accel.tri_ids[k]];
        accel.tri_normals[k] = encode_normals(mesh.normals[idx.x], mesh.normals[idx.y], mesh.normals[idx.z]);
      });
    }
    return;
  }
  std::vector<glm::mat3> normal_matrix;
  for (const Instance& inst : scene.instances)
    normal_matrix.push_back(glm::transpose(glm::inverse(glm::mat3(inst.object_to_world))));
  ls::parallel_for(size_t(0), accel.tris.size(), [&](size_t k) {
    const uint32_t inst = accel.tri_instances[k];
    const Mesh& mesh = scene.meshes[scene.instances[inst].mesh];
    const glm::uvec3 idx = mesh.triangles[accel.tri_ids[k]];
    const glm::mat3& nm = normal_matrix[inst];
    accel.tri_normals[k] = encode_normals(nm * mesh.normals[idx.x], nm * mesh.normals[idx.y], nm * mesh.normals[idx.z]);
  });
}

}  // namespace

size_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? size_t(pages) * size_t(page) : size_t(8) << 30;
}

size_t estimate_line_space_bytes(size_t ls_nodes, int n) {
  const double shafts = 30.0 * std::pow(double(n), 4.0);
  return size_t(double(ls_nodes) * (shafts * 4.0 + double(sizeof(lsk::LsNode))));
}

void layout_line_space(const Scene& scene, const LsOptions& options, Accel& accel) {
  const int depth = accel.spec.depth;
  const uint32_t n = uint32_t(accel.spec.subdivision);
  const uint32_t shafts = lsk::ls_shaft_count(n);
  accel.ls_options = options;

  // Subtree ranges and depths: children always follow their parent in the node array.
  const size_t node_count = accel.nodes.size();
  std::vector<Range> range(node_count);
  std::vector<int> node_depth(node_count, -1);
  for (size_t i = node_count; i-- > 0;) {
    const lsk::BvhNode& node = accel.nodes[i];
    if (node.count > 0) range[i] = Range{node.first, node.count};
    else range[i] = Range{range[node.first].first, range[node.first].count + range[node.first + 1].count};
  }
  std::vector<uint32_t> roots;
  if (accel.spec.two_level()) {
    for (uint32_t r : accel.object_roots)
      if (r != lsk::LS_INVALID) roots.push_back(r);
  } else {
    roots.push_back(0);
  }
  for (uint32_t r : roots) node_depth[r] = 0;
  for (size_t i = 0; i < node_count; ++i) {
    const lsk::BvhNode& node = accel.nodes[i];
    if (node.count == 0 && node_depth[i] >= 0) node_depth[node.first] = node_depth[node.first + 1] = node_depth[i] + 1;
  }

  // The LS nodes: depth D, enough triangles, a usable box.
  std::vector<uint32_t> chosen;
  for (size_t i = 0; i < node_count; ++i)
    if (node_depth[i] == depth && range[i].count >= std::max<uint32_t>(1, options.min_triangles)) chosen.push_back(uint32_t(i));

  const size_t budget = options.max_memory ? options.max_memory : physical_memory_bytes() / 2;
  const size_t estimate = estimate_line_space_bytes(chosen.size(), int(n));
  if (estimate > budget)
    throw InputError("structure '" + accel.spec.name() + "': its Line Space would take about " +
                     std::to_string(estimate >> 20) + " MiB (" + std::to_string(chosen.size()) + " LS nodes x " +
                     std::to_string(shafts) + " shafts), over the budget of " + std::to_string(budget >> 20) +
                     " MiB: lower N or D, or raise --max-memory");

  accel.node_ls.assign(node_count, lsk::LS_INVALID);
  uint32_t words = 0;
  for (uint32_t node : chosen) {
    lsk::LsNode ls{};
    if (!ls_box(accel.nodes[node], ls.lo, ls.hi)) continue;
    ls.scale = float(n) / (ls.hi - ls.lo);
    ls.range_first = range[node].first;
    ls.range_count = range[node].count;
    ls.bytes = candidate_bytes(ls.range_count, options.paper_candidates);
    ls.node = node;
    ls.candidates = words;
    words += uint32_t((uint64_t(shafts) * ls.bytes + 3) / 4);
    accel.node_ls[node] = uint32_t(accel.ls_nodes.size());
    accel.ls_nodes.push_back(ls);
  }
  accel.ls_candidates.assign(words, 0xFFFFFFFFu);  // all ones: every shaft empty until found
  compute_triangle_normals(scene, range, accel);

  LsBuildInfo& info = accel.ls_info;
  info = LsBuildInfo{};
  info.ls_nodes = accel.ls_nodes.size();
  info.shafts_per_ls = shafts;
  info.empty_shafts = info.ls_nodes * size_t(shafts);
  info.candidate_bytes = size_t(words) * 4;
  info.candidate_bytes_paper = info.ls_nodes * size_t(shafts) * 4;
  info.candidate_bytes_compact = 0;
  for (const lsk::LsNode& ls : accel.ls_nodes)
    info.candidate_bytes_compact += (uint64_t(shafts) * candidate_bytes(ls.range_count, false) + 3) / 4 * 4;
}

size_t pack_ls_candidates(Accel& accel, size_t ls_index, const uint32_t* prims) {
  const lsk::LsNode& ls = accel.ls_nodes[ls_index];
  const uint32_t shafts = uint32_t(accel.ls_info.shafts_per_ls);
  size_t empty = 0;
  uint32_t* out = accel.ls_candidates.data() + ls.candidates;
  const uint32_t bits = ls.bytes * 8, per_word = 4 / ls.bytes;
  const uint32_t mask = bits == 32 ? 0xFFFFFFFFu : (1u << bits) - 1u;
  for (uint32_t s = 0; s < shafts; ++s) {
    const bool none = prims[s] == lsk::LS_INVALID;
    const uint32_t v = none ? mask : prims[s] - ls.range_first;  // local to the node's triangle range
    empty += none;
    uint32_t& w = out[s / per_word];
    const uint32_t shift = (s % per_word) * bits;
    w = (w & ~(mask << shift)) | ((v & mask) << shift);
  }
  return empty;
}

void build_line_space(const Scene& scene, const LsOptions& options, Accel& accel) {
  const auto start = std::chrono::steady_clock::now();
  layout_line_space(scene, options, accel);
  const uint32_t n = uint32_t(accel.spec.subdivision);
  const uint32_t shafts = uint32_t(accel.ls_info.shafts_per_ls);

  // The candidate search, every shaft of every LS node, in parallel.
  lsk::TraceContext context = accel.context();
  context.ls_enabled = 0;
  const float inv_n = 1.0f / float(n);
  const uint32_t instance = ls_search_instance(accel);
  std::atomic<size_t> empty{0}, nodes_done{0};
  std::mutex progress_mutex;
  ls::parallel_for(size_t(0), accel.ls_nodes.size(), [&](size_t li) {
    const lsk::LsNode ls_node = accel.ls_nodes[li];  // (not `ls`: that would hide namespace ls)
    std::vector<uint32_t> prims(shafts);
    ls::parallel_for(tbb::blocked_range<uint32_t>(0, shafts, 512), [&](const tbb::blocked_range<uint32_t>& r) {
      throw_if_interrupted();  // TBB cancels the other blocks and rethrows in the caller
      lsk::TraceContext c = context;
      for (uint32_t s = r.begin(); s != r.end(); ++s)
        prims[s] = c.ls_find_candidate(ls_node.node, ls_node, s, n, inv_n, uint32_t(options.further_rays), instance);
    });
    empty += pack_ls_candidates(accel, li, prims.data());  // nodes own disjoint words
    const size_t done = ++nodes_done;
    if (options.progress && progress_mutex.try_lock()) {  // never wait: a busy reporter skips a tick
      options.progress(done, accel.ls_nodes.size());
      progress_mutex.unlock();
    }
  });

  accel.ls_info.empty_shafts = empty.load();
  accel.ls_info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

uint32_t ls_search_instance(const Accel& accel) { return accel.spec.two_level() ? 0u : lsk::LS_INVALID; }

}  // namespace ls
