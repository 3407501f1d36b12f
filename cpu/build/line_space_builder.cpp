#include "cpu/build/line_space_builder.h"

#include "common/base/huge_pages.h"
#include "common/base/interrupt.h"
#include "common/base/memory_budget.h"
#include "common/base/parallel.h"
#include "common/structure/accel.h"
#include "cpu/trace/fast_tracer.h"

#include <glm/gtc/packing.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <set>
#include <stdexcept>

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

glm::uvec3 encode_normals(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  auto enc = [](glm::vec3 n) -> uint32_t {
    const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) return glm::packSnorm2x16(glm::vec2(0.0f));  // decodes to +z
    n /= l1;
    glm::vec2 e(n.x, n.y);
    if (n.z < 0.0f)
      e = glm::vec2((1.0f - std::fabs(n.y)) * (n.x >= 0.0f ? 1.0f : -1.0f), (1.0f - std::fabs(n.x)) * (n.y >= 0.0f ? 1.0f : -1.0f));
    return glm::packSnorm2x16(e);
  };
  return glm::uvec3(enc(a), enc(b), enc(c));
}

}  // namespace

lsk::LsRecord make_ls_record(const lsk::Triangle& tri, const glm::uvec3& normals, uint32_t id) {
  lsk::LsRecord r{};
  r.p0 = glm::vec3(tri.v0);
  r.normal0 = normals.x;
  r.normal1 = normals.y;
  r.normal2 = normals.z;
  r.id = id;
  // In double: the rows are 1 / |edge| in size, and the cross product of float edges neither over-
  // nor underflows there.
  const glm::dvec3 p0(tri.v0), e1 = glm::dvec3(tri.v1) - p0, e2 = glm::dvec3(tri.v2) - p0;
  const glm::dvec3 n = glm::cross(e1, e2);
  const double nn = glm::dot(n, n);
  if (!(nn > 0.0) || !std::isfinite(nn)) return r;  // degenerate: n = 0, refused as parallel
  const glm::vec3 unit(n / std::sqrt(nn));
  const glm::vec3 b1(glm::cross(e2, n) / nn), b2(glm::cross(n, e1) / nn);
  const auto finite = [](const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  if (!finite(unit) || !finite(b1) || !finite(b2)) return r;
  r.n = unit;
  r.b1 = b1;
  r.b2 = b2;
  return r;
}

void compute_line_space_records(const Scene& scene, const BvhSubtrees& subtrees, const LsBuildOptions& options, Accel& accel) {
  accel.ls_records.clear();
  resize_huge(accel.ls_records, accel.tris.size());  // read at random by lookups: 2 MB pages spare TLB misses
  if (accel.spec.two_level()) {
    for (size_t m = 0; m < accel.object_roots.size(); ++m) {
      if (accel.object_roots[m] == lsk::LS_INVALID || object_line_space(accel, options, m).n <= 0) continue;
      const Mesh& mesh = scene.meshes[m];
      const uint32_t root = accel.object_roots[m];
      ls::parallel_for(subtrees.first[root], subtrees.first[root] + subtrees.count[root], [&](uint32_t k) {
        const glm::uvec3 idx = mesh.triangles[accel.tri_ids[k]];
        accel.ls_records[k] =
            make_ls_record(accel.tris[k], encode_normals(mesh.normals[idx.x], mesh.normals[idx.y], mesh.normals[idx.z]), accel.tri_ids[k]);
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
    accel.ls_records[k] = make_ls_record(
        accel.tris[k], encode_normals(nm * mesh.normals[idx.x], nm * mesh.normals[idx.y], nm * mesh.normals[idx.z]), accel.tri_ids[k]);
  });
}

size_t estimate_line_space_bytes(size_t ls_nodes, int n) {
  const double shafts = 30.0 * std::pow(double(n), 4.0);
  return size_t(double(ls_nodes) * (shafts * 4.0 + double(sizeof(lsk::LsNode))));
}

BvhSubtrees bvh_subtrees(const Accel& accel) {
  // Children always follow their parent in the node array: ranges bottom-up, depths top-down.
  const size_t node_count = accel.nodes.size();
  BvhSubtrees t;
  t.first.resize(node_count);
  t.count.resize(node_count);
  t.depth.assign(node_count, -1);
  for (size_t i = node_count; i-- > 0;) {
    const lsk::BvhNode& node = accel.nodes[i];
    if (node.count > 0) {
      t.first[i] = node.first;
      t.count[i] = node.count;
    } else {
      t.first[i] = t.first[node.first];
      t.count[i] = t.count[node.first] + t.count[node.first + 1];
    }
  }
  for (uint32_t r : ls_roots(accel)) t.depth[r] = 0;
  for (size_t i = 0; i < node_count; ++i) {
    const lsk::BvhNode& node = accel.nodes[i];
    if (node.count == 0 && t.depth[i] >= 0) t.depth[node.first] = t.depth[node.first + 1] = t.depth[i] + 1;
  }
  return t;
}

std::vector<uint32_t> ls_roots(const Accel& accel) {
  if (!accel.spec.two_level()) return {0u};
  std::vector<uint32_t> roots;
  for (uint32_t r : accel.object_roots)
    if (r != lsk::LS_INVALID) roots.push_back(r);
  return roots;
}

std::vector<LsPlacement> place_line_spaces(const Accel& accel, const BvhSubtrees& subtrees, uint32_t root, int depth, int n,
                                           const LsBuildOptions& options) {
  std::vector<LsPlacement> placed;
  if (n <= 0 || accel.nodes.empty()) return placed;
  const uint32_t shafts = lsk::ls_shaft_count(uint32_t(n));
  const uint32_t min_triangles = std::max<uint32_t>(1, options.min_triangles);
  // The nodes at `depth` below `root`, in node order (a stack walk that stops at that depth).
  std::vector<uint32_t> stack{root}, found;
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    if (subtrees.depth[i] == depth) {
      if (subtrees.count[i] >= min_triangles) found.push_back(i);
      continue;
    }
    const lsk::BvhNode& node = accel.nodes[i];
    if (node.count == 0) {
      stack.push_back(node.first + 1);
      stack.push_back(node.first);
    }
  }
  std::sort(found.begin(), found.end());
  for (uint32_t node : found) {
    LsPlacement p;
    lsk::LsNode& ls = p.ls;
    ls = lsk::LsNode{};
    if (!ls_box(accel.nodes[node], ls.lo, ls.hi)) continue;
    ls.scale = float(n) / (ls.hi - ls.lo);
    ls.range_first = subtrees.first[node];
    ls.range_count = subtrees.count[node];
    ls.bytes = candidate_bytes(ls.range_count, options.paper_candidates);
    ls.node = node;
    ls.n = uint32_t(n);
    ls.inv_n = 1.0f / float(n);
    p.words = uint32_t((uint64_t(shafts) * ls.bytes + 3) / 4);
    placed.push_back(p);
  }
  return placed;
}

size_t placement_bytes(const std::vector<LsPlacement>& placed) {
  size_t bytes = 0;
  for (const LsPlacement& p : placed) bytes += sizeof(lsk::LsNode) + size_t(p.words) * 4;
  return bytes;
}

size_t line_space_fixed_bytes(const Accel& accel) {
  return accel.nodes.size() * sizeof(uint32_t) + accel.tris.size() * sizeof(lsk::LsRecord);
}

ObjectLs object_line_space(const Accel& accel, const LsBuildOptions& options, size_t mesh) {
  if (!options.objects.empty()) return mesh < options.objects.size() ? options.objects[mesh] : ObjectLs{};
  return ObjectLs{accel.spec.depth, accel.spec.subdivision};
}

namespace {
std::atomic<size_t> layouts{0};
}  // namespace

size_t line_space_layouts() { return layouts.load(); }

void layout_line_space_nodes(const LsBuildOptions& options, const Limits& limits, const BvhSubtrees& subtrees, Accel& accel) {
  ++layouts;
  accel.ls_options = options;
  // Every BVH's LS nodes, roots in node order: an object's own D and N (2L), or the structure's.
  std::vector<LsPlacement> placed;
  double estimate = 0.0;
  if (accel.spec.two_level()) {
    for (size_t m = 0; m < accel.object_roots.size(); ++m) {
      if (accel.object_roots[m] == lsk::LS_INVALID) continue;
      const ObjectLs o = object_line_space(accel, options, m);
      std::vector<LsPlacement> p = place_line_spaces(accel, subtrees, accel.object_roots[m], o.depth, o.n, options);
      estimate += double(estimate_line_space_bytes(p.size(), o.n));
      placed.insert(placed.end(), p.begin(), p.end());
    }
    std::sort(placed.begin(), placed.end(), [](const LsPlacement& a, const LsPlacement& b) { return a.ls.node < b.ls.node; });
  } else {
    placed = place_line_spaces(accel, subtrees, 0u, accel.spec.depth, accel.spec.subdivision, options);
    estimate = double(estimate_line_space_bytes(placed.size(), accel.spec.subdivision));
  }

  const size_t budget = memory_budget(limits.max_memory);
  if (estimate > double(budget)) {
    const std::string shape = accel.spec.line_space() && accel.spec.subdivision > 0 && options.objects.empty()
                                  ? std::to_string(placed.size()) + " LS nodes x " +
                                        std::to_string(lsk::ls_shaft_count(uint32_t(accel.spec.subdivision))) + " shafts"
                                  : std::to_string(placed.size()) + " LS nodes";
    throw InputError("structure '" + accel.spec.name() + "': its Line Space would take about " + mib_text(estimate) + " (" +
                     shape + "), over the budget of " + mib_budget_text(double(budget)) + ": lower N or D, or raise --max-memory");
  }

  accel.node_ls.assign(accel.nodes.size(), lsk::LS_INVALID);
  accel.ls_nodes.clear();
  uint32_t words = 0;
  LsBuildInfo& info = accel.ls_info;
  info = LsBuildInfo{};
  std::set<uint32_t> subdivisions;
  for (LsPlacement& p : placed) {
    p.ls.candidates = words;
    words += p.words;
    accel.node_ls[p.ls.node] = uint32_t(accel.ls_nodes.size());
    accel.ls_nodes.push_back(p.ls);
    const size_t shafts = lsk::ls_shaft_count(p.ls.n);
    info.shafts += shafts;
    info.candidate_bytes_paper += shafts * 4;
    info.candidate_bytes_compact += (uint64_t(shafts) * candidate_bytes(p.ls.range_count, false) + 3) / 4 * 4;
    subdivisions.insert(p.ls.n);
  }
  accel.ls_candidates.clear();
  reserve_huge(accel.ls_candidates, words);  // read at random by lookups, like the records
  accel.ls_candidates.assign(words, 0xFFFFFFFFu);  // all ones: every shaft empty until found
  info.ls_nodes = accel.ls_nodes.size();
  info.shafts_per_ls = subdivisions.size() == 1 ? lsk::ls_shaft_count(*subdivisions.begin())
                       : subdivisions.empty() && accel.spec.subdivision > 0 ? lsk::ls_shaft_count(uint32_t(accel.spec.subdivision))
                                                                            : 0;
  info.empty_shafts = info.shafts;
  info.candidate_bytes = size_t(words) * 4;
}

void layout_line_space(const Scene& scene, const LsBuildOptions& options, const Limits& limits, Accel& accel) {
  const BvhSubtrees subtrees = bvh_subtrees(accel);
  layout_line_space_nodes(options, limits, subtrees, accel);
  compute_line_space_records(scene, subtrees, options, accel);
}

void store_ls_candidate(Accel& accel, size_t ls_index, uint32_t shaft, uint32_t prim) {
  const lsk::LsNode& ls = accel.ls_nodes[ls_index];
  const uint32_t bits = ls.bytes * 8, per_word = 4 / ls.bytes;
  const uint32_t mask = bits == 32 ? 0xFFFFFFFFu : (1u << bits) - 1u;
  const uint32_t v = prim == lsk::LS_INVALID ? mask : prim - ls.range_first;  // local to the node's triangle range
  uint32_t& w = accel.ls_candidates[ls.candidates + shaft / per_word];
  const uint32_t shift = (shaft % per_word) * bits;
  w = (w & ~(mask << shift)) | ((v & mask) << shift);
}

size_t pack_ls_candidates(Accel& accel, size_t ls_index, const uint32_t* prims) {
  const uint32_t shafts = lsk::ls_shaft_count(accel.ls_nodes[ls_index].n);
  size_t empty = 0;
  for (uint32_t s = 0; s < shafts; ++s) {
    store_ls_candidate(accel, ls_index, s, prims[s]);
    empty += prims[s] == lsk::LS_INVALID;
  }
  return empty;
}

void search_line_space(const LsBuildOptions& options, Accel& accel) {
  const auto start = std::chrono::steady_clock::now();
  // The candidate search, every shaft of every LS node, in parallel: on the fast path where the
  // structure has one (the same candidates), else with the reference kernels.
  lsk::TraceContext context = trace_context(accel);  // the search asks no Line Space
  const FastTracer* fast = accel.fast.get();
  context.ls_enabled = 0;
  const uint32_t instance = ls_search_instance(accel);
  std::atomic<size_t> empty{0}, nodes_done{0};
  std::mutex progress_mutex;
  ls::parallel_for(size_t(0), accel.ls_nodes.size(), [&](size_t li) {
    const lsk::LsNode ls_node = accel.ls_nodes[li];  // (not `ls`: that would hide namespace ls)
    const uint32_t shafts = lsk::ls_shaft_count(ls_node.n);
    std::vector<uint32_t> prims(shafts);
    const std::vector<lsk::vec3> centres = ls_patch_centres(ls_node);
    ls::parallel_for(tbb::blocked_range<uint32_t>(0, shafts, 512), [&](const tbb::blocked_range<uint32_t>& r) {
      throw_if_interrupted();  // TBB cancels the other blocks and rethrows in the caller
      lsk::TraceContext c = context;
      if (fast)
        fast->find_candidates(c, ls_node, centres.data(), r.begin(), r.end(), uint32_t(options.further_rays), instance,
                              prims.data() + r.begin());
      else
        for (uint32_t s = r.begin(); s != r.end(); ++s)
          prims[s] = c.ls_find_candidate(ls_node.node, ls_node, s, uint32_t(options.further_rays), instance);
    });
    empty += pack_ls_candidates(accel, li, prims.data());  // nodes own disjoint words
    const size_t done = ++nodes_done;
    if (options.progress && done < accel.ls_nodes.size() && progress_mutex.try_lock()) {  // never wait: skip a tick
      options.progress(done, accel.ls_nodes.size());
      progress_mutex.unlock();
    }
  });
  if (options.progress && !accel.ls_nodes.empty()) options.progress(accel.ls_nodes.size(), accel.ls_nodes.size());  // once
  accel.ls_info.empty_shafts = empty.load();
  accel.ls_info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void build_line_space(const Scene& scene, const LsBuildOptions& options, const Limits& limits, Accel& accel) {
  const auto start = std::chrono::steady_clock::now();
  layout_line_space(scene, options, limits, accel);
  search_line_space(options, accel);
  accel.ls_info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::vector<lsk::vec3> ls_patch_centres(const lsk::LsNode& ls) {
  const lsk::vec4 s = lsk::ls_search_offsets(0u);  // (0.5, 0.5, 0.5, 0.5): one table for both ends
  if (s.x != s.z || s.y != s.w) throw std::logic_error("ls_patch_centres: search ray 0 no longer joins like points");
  std::vector<lsk::vec3> centres(6u * ls.n * ls.n);
  for (uint32_t p = 0; p < centres.size(); ++p) centres[p] = lsk::ls_patch_point(ls.lo, ls.hi, p, ls.n, ls.inv_n, s.x, s.y);
  return centres;
}

uint32_t ls_search_instance(const Accel& accel) { return accel.spec.two_level() ? 0u : lsk::LS_INVALID; }

}  // namespace ls
