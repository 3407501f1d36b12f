#include "cpu/app/lookup_timing.h"

#include "common/model/scene.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <random>

namespace ls {

namespace {

struct LookupSample {
  uint32_t ray, node, ls;
};

// The reference kernel's walk, nearest child first, recording each lookup before making it.
std::vector<LookupSample> collect_lookups(lsk::TraceContext& c, const std::vector<lsk::Ray>& rays) {
  std::vector<LookupSample> samples;
  std::vector<uint32_t> stack;
  for (uint32_t r = 0; r < rays.size(); ++r) {
    const lsk::Ray& ray = rays[r];
    const lsk::vec3 inv = lsk::safe_reciprocal(ray.dir);
    lsk::Hit hit = lsk::empty_hit(ray);
    uint32_t prim = lsk::LS_INVALID;
    stack.assign(1, 0u);
    while (!stack.empty()) {
      const uint32_t n = stack.back();
      stack.pop_back();
      const lsk::BvhNode& node = c.nodes[n];
      float t;
      if (!lsk::ray_box(ray.origin, inv, ray.tmin, hit.t, node.lo, node.hi, t)) continue;
      const uint32_t ls = c.node_ls[n];
      if (ls != lsk::LS_INVALID) {
        samples.push_back({r, n, ls});
        if (c.ls_lookup(ls, node.lo, node.hi, ray.origin, ray.dir, inv, ray.tmin, ray.tmax, lsk::LS_INVALID, hit, prim) !=
            lsk::TraceContext::LS_FALLBACK)
          continue;
      }
      if (ls != lsk::LS_INVALID || node.count > 0) {  // a refused lookup's subtree, or a leaf: exactly
        c.trace_bvh(n, ray.origin, ray.dir, ray.tmin, ray.tmax, lsk::LS_INVALID, false, false, hit, prim);
        continue;
      }
      float tl = 0.0f, tr = 0.0f;
      const lsk::BvhNode& l = c.nodes[node.first];
      const lsk::BvhNode& rn = c.nodes[node.first + 1];
      const bool hl = lsk::ray_box(ray.origin, inv, ray.tmin, hit.t, l.lo, l.hi, tl);
      const bool hr = lsk::ray_box(ray.origin, inv, ray.tmin, hit.t, rn.lo, rn.hi, tr);
      const bool left_first = !hr || (hl && tl <= tr);
      stack.push_back(left_first ? node.first + 1 : node.first);
      stack.push_back(left_first ? node.first : node.first + 1);
    }
  }
  return samples;
}

struct Timing {
  double ns = 0.0;
  uint64_t checksum = 0;  // keeps the answers alive
};

// ns per lookup over `order` (indices into samples), the best of `repeat` passes.
Timing time_order(lsk::TraceContext& c, const std::vector<lsk::Ray>& rays, const std::vector<lsk::vec3>& inv,
                  const std::vector<LookupSample>& samples, const std::vector<uint32_t>& order, int repeat) {
  Timing best;
  for (int pass = 0; pass < repeat; ++pass) {
    uint64_t sum = 0;
    const auto start = std::chrono::steady_clock::now();
    for (uint32_t i : order) {
      const LookupSample& s = samples[i];
      const lsk::Ray& ray = rays[s.ray];
      lsk::Hit hit = lsk::empty_hit(ray);
      uint32_t prim = lsk::LS_INVALID;
      const lsk::BvhNode& node = c.nodes[s.node];
      sum += c.ls_lookup(s.ls, node.lo, node.hi, ray.origin, ray.dir, inv[s.ray], ray.tmin, ray.tmax, lsk::LS_INVALID, hit, prim);
      sum += prim;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double ns = seconds / double(order.size()) * 1e9;
    if (pass == 0 || ns < best.ns) best.ns = ns;
    best.checksum += sum;
  }
  return best;
}

}  // namespace

void time_lookups(const Accel& accel, const LsLookup& lookup, const std::vector<lsk::Ray>& rays, int repeat) {
  if (accel.ls_nodes.empty()) throw InputError("--lookups needs a Line Space structure");
  if (!accel.instances.empty()) throw InputError("--lookups times flat structures only (f-ls:D:N)");
  lsk::TraceContext c = trace_context(accel, lookup);
  const std::vector<LookupSample> samples = collect_lookups(c, rays);
  if (samples.empty()) throw InputError("the rays make no lookups");
  const lsk::LsCounters counts = c.ls_counters;
  std::vector<lsk::vec3> inv(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) inv[i] = lsk::safe_reciprocal(rays[i].dir);
  std::vector<uint32_t> order(samples.size());
  std::iota(order.begin(), order.end(), 0u);
  const Timing traversal = time_order(c, rays, inv, samples, order, repeat);
  // Cached: the first 1,024 lookups (their nodes, words and records fit the L2 cache) 64 times over.
  std::vector<uint32_t> small;
  for (int k = 0; k < 64; ++k)
    for (uint32_t i = 0; i < std::min<size_t>(order.size(), 1024); ++i) small.push_back(i);
  const Timing cached = time_order(c, rays, inv, samples, small, repeat);
  std::shuffle(order.begin(), order.end(), std::mt19937(1));
  const Timing shuffled = time_order(c, rays, inv, samples, order, repeat);

  size_t shafts = 0;
  for (const lsk::LsNode& n : accel.ls_nodes) shafts += size_t(30) * n.n * n.n * n.n * n.n;
  const double candidate_bytes = double(accel.ls_candidates.size()) * 4.0 / double(shafts);
  const double record_bytes = double(accel.ls_records.size()) * double(sizeof(lsk::LsRecord)) / double(shafts);
  const double per = 100.0 / double(counts.lookups);
  std::printf("%zu lookups for %zu rays (%.2f a ray): %.0f %% accepted, %.0f %% empty, %.0f %% refused\n", samples.size(),
              rays.size(), double(samples.size()) / double(rays.size()), counts.accepted * per, counts.empty * per,
              (counts.lookups - counts.accepted - counts.empty) * per);
  std::printf("ns per lookup (best of %d, one thread): %.1f in traversal order, %.1f shuffled, %.1f cached\n", repeat,
              traversal.ns, shuffled.ns, cached.ns);
  std::printf("bytes per shaft: %.2f candidate + %.2f record (%zu shafts, %zu records of %zu B)\n", candidate_bytes,
              record_bytes, shafts, accel.ls_records.size(), sizeof(lsk::LsRecord));
  if ((traversal.checksum ^ cached.checksum ^ shuffled.checksum) == 0x5eed) std::printf("\n");  // never: keeps the sums
}

}  // namespace ls
