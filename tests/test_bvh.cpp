// The binned-SAH BVH builder (cpu/bvh_builder) and the F-BVH / 2L-BVH arrays built from it
// (cpu/accel): structural invariants on random and degenerate box sets, determinism, and the
// bookkeeping of flat and two-level structures against hand-built scenes.
#include <catch2/catch.hpp>

#include "common/model/scene.h"
#include "common/model/structure_name.h"
#include "common/structure/accel.h"
#include "cpu/build/build_accel.h"
#include "cpu/build/bvh_builder.h"
#include "tests/test_helpers.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

using ls::Bounds;
using ls::BvhBuildOptions;
using ls::BvhBuildResult;
using namespace test_support;  // Rng: floats from the top 24 bits of a draw

namespace {

Bounds box_of(const glm::vec3& lo, const glm::vec3& hi) {
  Bounds b;
  b.grow(lo);
  b.grow(hi);
  return b;
}

bool same_bits(const glm::vec3& a, const glm::vec3& b) { return std::memcmp(&a, &b, sizeof(glm::vec3)) == 0; }

bool inside(const Bounds& inner, const glm::vec3& lo, const glm::vec3& hi) {
  return glm::all(glm::greaterThanEqual(inner.lo, lo)) && glm::all(glm::lessThanEqual(inner.hi, hi));
}

struct TreeStats {
  size_t leaves = 0;
  int depth = 0;
  size_t largest_leaf = 0;
};

// Checks every structural invariant of a BVH over `prim_boxes` (indexed by position in BVH order, i.e.
// prim_boxes[k] is the box of the primitive at position k).  Node indices and primitive indices are
// absolute; the tree occupies nodes [node_begin, node_end) and primitives [prim_begin, prim_end).
// Returns statistics; failures are reported through Catch.
TreeStats check_tree(const std::vector<lsk::BvhNode>& nodes, uint32_t root, uint32_t node_begin, uint32_t node_end,
                     const std::vector<Bounds>& prim_boxes, uint32_t prim_begin, uint32_t prim_end, int max_leaf_size) {
  TreeStats stats;
  REQUIRE(root >= node_begin);
  REQUIRE(root < node_end);
  std::vector<int> visits(node_end - node_begin, 0);
  std::vector<int> covered(prim_end - prim_begin, 0);
  size_t bad_box = 0, bad_child = 0, bad_leaf = 0, bad_contig = 0, bad_index = 0;

  // Iterative walk computing each node's primitive range; (node, depth).
  struct Item {
    uint32_t node;
    int depth;
  };
  // The range of a subtree, computed bottom-up with an explicit post-order.
  std::vector<std::pair<uint32_t, uint32_t>> range(node_end - node_begin, {0u, 0u});
  std::vector<Item> stack = {{root, 0}};
  std::vector<Item> post;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const uint32_t local = it.node - node_begin;
    ++visits[local];
    if (visits[local] > 1) continue;  // reported below
    post.push_back(it);
    stats.depth = std::max(stats.depth, it.depth);
    const lsk::BvhNode& n = nodes[it.node];
    if (n.count > 0) {
      ++stats.leaves;
      stats.largest_leaf = std::max<size_t>(stats.largest_leaf, n.count);
      if (int(n.count) > max_leaf_size) ++bad_leaf;
      if (n.first < prim_begin || n.first + n.count > prim_end || n.first + n.count < n.first) {
        ++bad_index;
        continue;
      }
      for (uint32_t k = n.first; k < n.first + n.count; ++k) ++covered[k - prim_begin];
      range[local] = {n.first, n.first + n.count};
    } else {
      if (n.first < node_begin || n.first + 1 >= node_end || n.first == it.node || n.first + 1 == it.node) {
        ++bad_index;
        continue;
      }
      stack.push_back({n.first + 1, it.depth + 1});
      stack.push_back({n.first, it.depth + 1});
    }
  }
  CHECK(bad_index == 0);
  if (bad_index) return stats;
  // Post-order: children after parents in `post`, so walk it backwards.
  for (auto it = post.rbegin(); it != post.rend(); ++it) {
    const lsk::BvhNode& n = nodes[it->node];
    const uint32_t local = it->node - node_begin;
    Bounds expected;
    if (n.count > 0) {
      for (uint32_t k = n.first; k < n.first + n.count; ++k) expected.grow(prim_boxes[k]);
    } else {
      const lsk::BvhNode& l = nodes[n.first];
      const lsk::BvhNode& r = nodes[n.first + 1];
      // Children inside the parent.
      if (!inside(box_of(l.lo, l.hi), n.lo, n.hi) || !inside(box_of(r.lo, r.hi), n.lo, n.hi)) ++bad_child;
      const auto lr = range[n.first - node_begin];
      const auto rr = range[n.first + 1 - node_begin];
      // The two children's ranges are adjacent: the node covers one contiguous range.
      if (lr.second != rr.first || lr.first >= lr.second || rr.first >= rr.second) ++bad_contig;
      range[local] = {lr.first, rr.second};
      for (uint32_t k = lr.first; k < rr.second; ++k) expected.grow(prim_boxes[k]);
    }
    // Node box = union of its primitives' boxes, bit for bit.
    if (!same_bits(expected.lo, n.lo) || !same_bits(expected.hi, n.hi)) ++bad_box;
  }
  CHECK(bad_box == 0);
  CHECK(bad_child == 0);
  CHECK(bad_contig == 0);
  CHECK(bad_leaf == 0);
  // Every node of the array reached exactly once (a tree, no orphans, no sharing).
  size_t unreached = 0, shared = 0;
  for (int v : visits) {
    if (v == 0) ++unreached;
    if (v > 1) ++shared;
  }
  CHECK(unreached == 0);
  CHECK(shared == 0);
  // Leaf ranges disjoint and covering every primitive exactly once.
  size_t uncovered = 0, doubly = 0;
  for (int c : covered) {
    if (c == 0) ++uncovered;
    if (c > 1) ++doubly;
  }
  CHECK(uncovered == 0);
  CHECK(doubly == 0);
  // The root covers the whole range.
  CHECK(range[root - node_begin].first == prim_begin);
  CHECK(range[root - node_begin].second == prim_end);
  CHECK(stats.depth < lsk::TraceContext::LS_STACK_SIZE);
  return stats;
}

// All invariants of one build_bvh result over `boxes`, plus determinism (a second build is identical).
TreeStats check_build(const std::vector<Bounds>& boxes, const BvhBuildOptions& options = {}) {
  const BvhBuildResult r = ls::build_bvh(boxes, options);
  const size_t n = boxes.size();
  // order is a permutation of [0, n).
  REQUIRE(r.order.size() == n);
  std::vector<uint32_t> sorted = r.order;
  std::sort(sorted.begin(), sorted.end());
  bool permutation = true;
  for (size_t i = 0; i < n; ++i) permutation = permutation && sorted[i] == i;
  REQUIRE(permutation);
  REQUIRE(!r.nodes.empty());
  // A binary tree with L leaves has 2L - 1 nodes; at most n leaves.
  std::vector<Bounds> ordered(n);
  for (size_t k = 0; k < n; ++k) ordered[k] = boxes[r.order[k]];
  const TreeStats stats = check_tree(r.nodes, 0, 0, uint32_t(r.nodes.size()), ordered, 0, uint32_t(n), options.max_leaf_size);
  CHECK(r.nodes.size() == 2 * stats.leaves - 1);
  CHECK(stats.leaves <= n);
  CHECK(r.max_depth == stats.depth);
  CHECK(r.max_depth < lsk::TraceContext::LS_STACK_SIZE);

  // Deterministic: a second build gives the same nodes and order, bit for bit.
  const BvhBuildResult again = ls::build_bvh(boxes, options);
  REQUIRE(again.nodes.size() == r.nodes.size());
  CHECK(std::memcmp(again.nodes.data(), r.nodes.data(), r.nodes.size() * sizeof(lsk::BvhNode)) == 0);
  CHECK(again.order == r.order);
  CHECK(again.max_depth == r.max_depth);
  return stats;
}

std::vector<Bounds> random_boxes(size_t n, uint32_t seed, float world = 10.0f, float size = 0.5f) {
  Rng rng(seed);
  std::vector<Bounds> boxes(n);
  for (Bounds& b : boxes) {
    const glm::vec3 c = rng.vec(-world, world);
    const glm::vec3 e = rng.vec(0.0f, size);
    b = box_of(c - e, c + e);
  }
  return boxes;
}

}  // namespace

TEST_CASE("build_bvh: random box sets", "[bvh]") {
  for (size_t n : {size_t(1), size_t(2), size_t(3), size_t(7), size_t(1000), size_t(100000)}) {
    INFO("n = " << n);
    const TreeStats s = check_build(random_boxes(n, uint32_t(1000 + n)));
    if (n == 1) {
      CHECK(s.leaves == 1);
      CHECK(s.depth == 0);
    }
    if (n >= 1000) CHECK(s.depth > 0);
  }
}

TEST_CASE("build_bvh: option variations", "[bvh]") {
  const std::vector<Bounds> boxes = random_boxes(3000, 77);
  for (int leaf : {1, 2, 4, 8, 16}) {
    for (int bins : {2, 8, 32, 64, 200}) {
      INFO("max_leaf_size " << leaf << ", bins " << bins);
      BvhBuildOptions o;
      o.max_leaf_size = leaf;
      o.bins = bins;
      const TreeStats s = check_build(boxes, o);
      CHECK(int(s.largest_leaf) <= leaf);
    }
  }
  // A shallow SAH limit forces object-median splits early; the invariants still hold.
  BvhBuildOptions o;
  o.sah_depth_limit = 3;
  check_build(boxes, o);
  o.sah_depth_limit = 0;
  check_build(boxes, o);
  // An expensive traversal makes the SAH prefer leaves (still bounded by max_leaf_size).
  o = BvhBuildOptions{};
  o.traversal_cost = 1000.0f;
  check_build(boxes, o);
}

TEST_CASE("build_bvh: degenerate inputs", "[bvh]") {
  SECTION("all boxes identical") {
    for (size_t n : {size_t(2), size_t(5), size_t(1000), size_t(20000)}) {
      INFO("n = " << n);
      std::vector<Bounds> boxes(n, box_of(glm::vec3(-1.0f, 2.0f, 3.0f), glm::vec3(0.5f, 2.5f, 7.0f)));
      check_build(boxes);
    }
  }
  SECTION("all centroids on a line") {
    Rng rng(5);
    for (const glm::vec3 axis : {glm::vec3(1, 0, 0), glm::vec3(0, 0, 1), glm::vec3(1, 1, 1)}) {
      std::vector<Bounds> boxes(5000);
      for (Bounds& b : boxes) {
        const glm::vec3 c = axis * rng.range(-100.0f, 100.0f);
        const glm::vec3 e = rng.vec(0.0f, 3.0f);
        b = box_of(c - e, c + e);
      }
      check_build(boxes);
    }
    // Evenly spaced equal boxes along one axis, and many boxes sharing few centroids.
    std::vector<Bounds> boxes;
    for (int i = 0; i < 4096; ++i) boxes.push_back(box_of(glm::vec3(float(i), 0, 0), glm::vec3(float(i) + 1.0f, 1, 1)));
    check_build(boxes);
    boxes.clear();
    for (int i = 0; i < 4096; ++i) boxes.push_back(box_of(glm::vec3(float(i % 3), 0, 0), glm::vec3(float(i % 3), 0, 0)));
    check_build(boxes);
  }
  SECTION("zero-extent point boxes") {
    Rng rng(6);
    std::vector<Bounds> boxes(10000);
    for (Bounds& b : boxes) {
      const glm::vec3 p = rng.vec(-1.0f, 1.0f);
      b = box_of(p, p);
    }
    check_build(boxes);
    // Points on a plane: flat node boxes.
    for (Bounds& b : boxes) {
      const glm::vec3 p(rng.range(-1.0f, 1.0f), rng.range(-1.0f, 1.0f), 0.0f);
      b = box_of(p, p);
    }
    check_build(boxes);
  }
  SECTION("one huge box among tiny ones") {
    std::vector<Bounds> boxes = random_boxes(5000, 8, 1.0f, 1e-4f);
    boxes.insert(boxes.begin() + 1234, box_of(glm::vec3(-1e6f), glm::vec3(1e6f)));
    check_build(boxes);
    boxes.push_back(box_of(glm::vec3(-1e30f, -1.0f, -1.0f), glm::vec3(1e30f, 1.0f, 1.0f)));
    check_build(boxes);
  }
  SECTION("exponentially spaced boxes push the SAH deep") {
    for (const float factor : {2.0f, 1.05f, 1.01f}) {
      std::vector<Bounds> boxes;
      float x = 1e-20f;
      while (x < 1e25f && boxes.size() < 30000) {
        boxes.push_back(box_of(glm::vec3(x, 0.0f, 0.0f), glm::vec3(x * 1.001f, 1e-3f * x, 1e-3f * x)));
        x *= factor;
      }
      INFO("factor " << factor << ", n = " << boxes.size());
      const TreeStats s = check_build(boxes);
      CHECK(s.depth < lsk::TraceContext::LS_STACK_SIZE);
    }
    // Nested boxes (each contains the next): the same centroid spread at every level.
    std::vector<Bounds> nested;
    float r = 1e20f;
    for (int i = 0; i < 2000; ++i, r *= 0.97f) nested.push_back(box_of(glm::vec3(r, 0, 0), glm::vec3(2.0f * r, r, r)));
    check_build(nested);
  }
  SECTION("exactly max_leaf_size + 1 boxes and random sizes around the leaf limit") {
    for (size_t n = 1; n <= 40; ++n) {
      INFO("n = " << n);
      check_build(random_boxes(n, uint32_t(n * 31)));
    }
  }
}

namespace {

float half_area_of(const Bounds& b) {
  if (b.empty()) return 0.0f;
  const glm::vec3 e = b.extent();
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

// The builder's split rule, recomputed by brute force at every node of `r` above the SAH depth limit:
// the centroid bins of the node's primitives, the SAH cost of every bin boundary on every axis from
// the primitives themselves (first minimum in axis, then bin order), the leaf-or-split decision, and
// that the left child holds exactly the primitives left of the chosen boundary.  Independent of the
// builder's binning, sweep and partition; the float arithmetic of the costs is the rule's own, so near
// ties are decided as the builder must decide them.  Returns the number of nodes checked.
size_t check_sah_choices(const std::vector<Bounds>& boxes, const BvhBuildResult& r, const BvhBuildOptions& o) {
  const int bins = std::clamp(o.bins, 2, 64);
  size_t checked = 0;
  // Each node's primitive range: [first, end) in r.order.
  std::function<std::pair<uint32_t, uint32_t>(uint32_t, int)> visit = [&](uint32_t index, int depth) {
    const lsk::BvhNode& node = r.nodes[index];
    std::pair<uint32_t, uint32_t> range;
    uint32_t mid = 0;  // where the left child's range ends
    if (node.count > 0) {
      range = {node.first, node.first + node.count};
    } else {
      const auto left = visit(node.first, depth + 1);
      const auto right = visit(node.first + 1, depth + 1);
      REQUIRE(left.second == right.first);
      range = {left.first, right.second};
      mid = left.second;
    }
    if (depth >= o.sah_depth_limit) return range;
    const uint32_t n = range.second - range.first;
    Bounds box, cb;
    for (uint32_t i = range.first; i < range.second; ++i) {
      box.grow(boxes[r.order[i]]);
      cb.grow(boxes[r.order[i]].centre());
    }
    glm::vec3 scale(0.0f);
    for (int a = 0; a < 3; ++a) {
      const float ext = cb.hi[a] - cb.lo[a];
      scale[a] = ext > 0.0f ? float(bins) * 0.99999f / ext : 0.0f;
    }
    auto bin_of = [&](uint32_t prim, int a) {
      return std::clamp(int((boxes[prim].centre()[a] - cb.lo[a]) * scale[a]), 0, bins - 1);
    };
    float best_cost = std::numeric_limits<float>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int a = 0; a < 3 && n > 1; ++a) {
      if (scale[a] == 0.0f) continue;
      for (int b = 0; b + 1 < bins; ++b) {
        Bounds lb, rb;
        uint32_t lc = 0;
        for (uint32_t i = range.first; i < range.second; ++i) {
          const uint32_t p = r.order[i];
          if (bin_of(p, a) <= b) {
            lb.grow(boxes[p]);
            ++lc;
          } else {
            rb.grow(boxes[p]);
          }
        }
        if (lc == 0 || lc == n) continue;
        const float cost = half_area_of(lb) * float(lc) + half_area_of(rb) * float(n - lc);
        if (cost < best_cost) { best_cost = cost; best_axis = a; best_bin = b; }
      }
    }
    INFO("node " << index << ", depth " << depth << ", " << n << " primitives");
    if (best_axis < 0) {  // nothing separates the centroids: a leaf unless over the leaf size (median)
      if (n <= uint32_t(o.max_leaf_size)) CHECK(node.count == n);
      return range;
    }
    const float parent_area = half_area_of(box);
    const float split_cost = parent_area > 0.0f ? o.traversal_cost + best_cost / parent_area : float(n);
    const bool leaf = n <= uint32_t(o.max_leaf_size) && float(n) <= split_cost;
    CHECK(node.count == (leaf ? n : 0u));
    if (leaf || node.count > 0) return range;
    bool sides_right = true;
    for (uint32_t i = range.first; i < range.second; ++i)
      sides_right = sides_right && (bin_of(r.order[i], best_axis) <= best_bin) == (i < mid);
    CHECK(sides_right);
    ++checked;
    return range;
  };
  visit(0, 0);
  return checked;
}

}  // namespace

TEST_CASE("build_bvh: every split is the binned SAH's choice, recomputed by brute force", "[bvh]") {
  struct Case {
    const char* name;
    std::vector<Bounds> boxes;
    BvhBuildOptions options;
  };
  std::vector<Case> cases;
  cases.push_back({"random 3000", random_boxes(3000, 11), {}});
  cases.push_back({"random 9000 (parallel binning above 4096)", random_boxes(9000, 12), {}});
  cases.push_back({"clustered", random_boxes(2000, 13, 1.0f, 2.0f), {}});
  BvhBuildOptions few;
  few.bins = 5;
  few.max_leaf_size = 1;
  cases.push_back({"5 bins, leaves of 1", random_boxes(1500, 14), few});
  BvhBuildOptions costly;
  costly.traversal_cost = 3.0f;
  costly.max_leaf_size = 8;
  cases.push_back({"traversal cost 3, leaves of 8", random_boxes(1500, 15), costly});
  std::vector<Bounds> grid;  // many equal costs: the first minimum must win
  for (int i = 0; i < 16; ++i)
    for (int j = 0; j < 16; ++j)
      for (int k = 0; k < 8; ++k) grid.push_back(box_of(glm::vec3(float(i), float(j), float(k)), glm::vec3(float(i) + 1.0f, float(j) + 1.0f, float(k) + 1.0f)));
  cases.push_back({"unit grid 16x16x8", grid, {}});
  std::vector<Bounds> signed_zero = random_boxes(500, 16);
  for (size_t i = 0; i < signed_zero.size(); i += 3) {
    signed_zero[i].lo.x = (i % 2) ? -0.0f : 0.0f;
    signed_zero[i].hi.x = std::max(signed_zero[i].hi.x, 0.5f);
  }
  cases.push_back({"boxes starting at +0 and -0", signed_zero, {}});
  for (const Case& c : cases) {
    INFO(c.name);
    const BvhBuildResult r = ls::build_bvh(c.boxes, c.options);
    CHECK(check_sah_choices(c.boxes, r, c.options) > c.boxes.size() / 8);
  }
}

TEST_CASE("build_bvh: zero boxes is an input error", "[bvh]") {
  CHECK_THROWS_AS(ls::build_bvh({}), ls::InputError);
}

// ---------------------------------------------------------------------------------------------------
// F-BVH and 2L-BVH through build_accel.

namespace {

glm::mat4 transform(const glm::vec3& translate, float angle, const glm::vec3& axis, const glm::vec3& scale) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  m = glm::rotate(m, angle, axis);
  return glm::scale(m, scale);
}

ls::Instance instance(uint32_t mesh, const glm::mat4& m) {
  ls::Instance inst;
  inst.mesh = mesh;
  inst.object_to_world = m;
  return inst;
}

ls::Scene base_scene() {
  ls::Scene s;
  s.name = "test";
  s.materials.push_back(ls::Material{});
  return s;
}

template <typename T>
size_t array_bytes(const std::vector<T>& v) {
  return v.size() * sizeof(T);
}

// Every array the structure uploads (the Line Space ones are empty or small for BVH structures).
size_t expected_bytes(const ls::Accel& a) {
  return array_bytes(a.nodes) + array_bytes(a.tris) + array_bytes(a.tri_ids) + array_bytes(a.tri_instances) +
         array_bytes(a.top_nodes) + array_bytes(a.instances) + array_bytes(a.node_ls) + array_bytes(a.ls_nodes) +
         array_bytes(a.ls_candidates) + array_bytes(a.ls_records);
}

bool same_tri(const lsk::Triangle& t, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  return same_bits(glm::vec3(t.v0), a) && same_bits(glm::vec3(t.v1), b) && same_bits(glm::vec3(t.v2), c) &&
         t.v0.w == 0.0f && t.v1.w == 0.0f && t.v2.w == 0.0f;
}

Bounds tri_box(const lsk::Triangle& t) {
  Bounds b;
  b.grow(glm::vec3(t.v0));
  b.grow(glm::vec3(t.v1));
  b.grow(glm::vec3(t.v2));
  return b;
}

// Invariants of a flat structure against its scene.
void check_flat(const ls::Scene& scene, const ls::Accel& a, int max_leaf_size = 4) {
  const size_t total = ls::triangle_count(scene);
  CHECK(a.world_triangles == total);
  CHECK(a.instance_count == scene.instances.size());
  REQUIRE(a.tris.size() == total);
  REQUIRE(a.tri_ids.size() == total);
  REQUIRE(a.tri_instances.size() == total);
  CHECK(a.top_nodes.empty());
  CHECK(a.instances.empty());
  // Every (instance, triangle) exactly once, with the world-space vertices of the scene.
  std::set<std::pair<uint32_t, uint32_t>> seen;
  size_t wrong_vertices = 0, out_of_range = 0;
  for (size_t k = 0; k < total; ++k) {
    const uint32_t inst = a.tri_instances[k], tri = a.tri_ids[k];
    if (inst >= scene.instances.size() || tri >= scene.meshes[scene.instances[inst].mesh].triangles.size()) {
      ++out_of_range;
      continue;
    }
    seen.insert({inst, tri});
    const ls::Instance& in = scene.instances[inst];
    const ls::Mesh& m = scene.meshes[in.mesh];
    const glm::uvec3 idx = m.triangles[tri];
    if (!same_tri(a.tris[k], ls::transform_point(in.object_to_world, m.positions[idx.x]),
                  ls::transform_point(in.object_to_world, m.positions[idx.y]),
                  ls::transform_point(in.object_to_world, m.positions[idx.z])))
      ++wrong_vertices;
  }
  CHECK(out_of_range == 0);
  CHECK(seen.size() == total);
  CHECK(wrong_vertices == 0);
  std::vector<Bounds> boxes(total);
  for (size_t k = 0; k < total; ++k) boxes[k] = tri_box(a.tris[k]);
  const TreeStats s = check_tree(a.nodes, 0, 0, uint32_t(a.nodes.size()), boxes, 0, uint32_t(total), max_leaf_size);
  CHECK(a.max_depth == s.depth);
  CHECK(a.bytes_total() == expected_bytes(a));
}

// Invariants of a two-level structure against its scene.
void check_two_level(const ls::Scene& scene, const ls::Accel& a, int max_leaf_size = 4) {
  CHECK(a.world_triangles == ls::triangle_count(scene));
  CHECK(a.instance_count == scene.instances.size());
  CHECK(a.tri_instances.empty());
  REQUIRE(a.object_roots.size() == scene.meshes.size());
  std::vector<bool> used(scene.meshes.size(), false);
  for (const ls::Instance& in : scene.instances) used[in.mesh] = true;
  const size_t unique = size_t(std::count(used.begin(), used.end(), true));
  CHECK(a.objects == unique);

  // Each used mesh: one BVH, stored once, over exactly its triangles in object space.
  size_t node_total = 0, tri_total = 0;
  std::vector<std::pair<uint32_t, uint32_t>> node_spans;  // [root, end) per used mesh, by root
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    INFO("mesh " << m);
    if (!used[m]) {
      CHECK(a.object_roots[m] == lsk::LS_INVALID);
      continue;
    }
    REQUIRE(a.object_roots[m] < a.nodes.size());
    node_spans.push_back({a.object_roots[m], uint32_t(m)});
  }
  std::sort(node_spans.begin(), node_spans.end());
  for (size_t i = 0; i < node_spans.size(); ++i) {
    const uint32_t root = node_spans[i].first;
    const uint32_t end = i + 1 < node_spans.size() ? node_spans[i + 1].first : uint32_t(a.nodes.size());
    const ls::Mesh& mesh = scene.meshes[node_spans[i].second];
    INFO("object " << node_spans[i].second << " nodes [" << root << ", " << end << ")");
    // The object's triangle range: the root's leaves cover one contiguous block; find it from the
    // smallest and largest leaf index reachable (check_tree then verifies exact coverage).
    uint32_t lo = UINT32_MAX, hi = 0;
    std::vector<uint32_t> stack = {root};
    size_t guard = 0;
    while (!stack.empty() && guard++ < a.nodes.size()) {
      const lsk::BvhNode n = a.nodes[stack.back()];
      stack.pop_back();
      if (n.count > 0) {
        lo = std::min(lo, n.first);
        hi = std::max(hi, n.first + n.count);
      } else if (n.first + 1 < a.nodes.size()) {
        stack.push_back(n.first);
        stack.push_back(n.first + 1);
      }
    }
    REQUIRE(hi <= a.tris.size());
    REQUIRE(hi - lo == mesh.triangles.size());
    std::vector<Bounds> boxes(a.tris.size());
    std::set<uint32_t> ids;
    size_t wrong_vertices = 0;
    for (uint32_t k = lo; k < hi; ++k) {
      boxes[k] = tri_box(a.tris[k]);
      const uint32_t id = a.tri_ids[k];
      REQUIRE(id < mesh.triangles.size());
      ids.insert(id);
      const glm::uvec3 idx = mesh.triangles[id];
      if (!same_tri(a.tris[k], mesh.positions[idx.x], mesh.positions[idx.y], mesh.positions[idx.z])) ++wrong_vertices;
    }
    CHECK(ids.size() == mesh.triangles.size());
    CHECK(wrong_vertices == 0);
    check_tree(a.nodes, root, root, end, boxes, lo, hi, max_leaf_size);
    // The same mesh built alone gives a BVH of the same size.
    std::vector<Bounds> mesh_boxes;
    for (const glm::uvec3& t : mesh.triangles) {
      Bounds b;
      b.grow(mesh.positions[t.x]);
      b.grow(mesh.positions[t.y]);
      b.grow(mesh.positions[t.z]);
      mesh_boxes.push_back(b);
    }
    BvhBuildOptions o;
    o.max_leaf_size = max_leaf_size;
    CHECK(ls::build_bvh(mesh_boxes, o).nodes.size() == end - root);
    node_total += end - root;
    tri_total += mesh.triangles.size();
  }
  CHECK(a.nodes.size() == node_total);
  CHECK(a.tris.size() == tri_total);
  CHECK(a.tri_ids.size() == tri_total);

  // Instances: each id once, pointing at its mesh's BVH, with the inverse transform.
  REQUIRE(a.instances.size() == scene.instances.size());
  std::set<uint32_t> inst_ids;
  for (const lsk::InstanceRecord& rec : a.instances) {
    REQUIRE(rec.instance < scene.instances.size());
    inst_ids.insert(rec.instance);
    const ls::Instance& in = scene.instances[rec.instance];
    CHECK(rec.object == in.mesh);
    CHECK(rec.root == a.object_roots[in.mesh]);
    // world_to_object * object_to_world ~ identity.
    const glm::mat4 w2o = glm::transpose(glm::mat4(rec.world_to_object0, rec.world_to_object1, rec.world_to_object2,
                                                   glm::vec4(0.0f, 0.0f, 0.0f, 1.0f)));
    const glm::mat4 id = w2o * in.object_to_world;
    float err = 0.0f;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) err = std::max(err, std::fabs(id[c][r] - (c == r ? 1.0f : 0.0f)));
    CHECK(err < 1e-5f);
  }
  CHECK(inst_ids.size() == scene.instances.size());

  // The top level: a valid BVH over the instances' world boxes, each containing its object's
  // transformed vertices.
  std::vector<Bounds> inst_boxes(a.instances.size());
  for (size_t k = 0; k < a.instances.size(); ++k) {
    const ls::Instance& in = scene.instances[a.instances[k].instance];
    const lsk::BvhNode& root = a.nodes[a.object_roots[in.mesh]];
    for (int corner = 0; corner < 8; ++corner) {
      const glm::vec3 p((corner & 1) ? root.hi.x : root.lo.x, (corner & 2) ? root.hi.y : root.lo.y,
                        (corner & 4) ? root.hi.z : root.lo.z);
      inst_boxes[k].grow(ls::transform_point(in.object_to_world, p));
    }
    size_t outside = 0;
    for (const glm::vec3& p : scene.meshes[in.mesh].positions) {
      const glm::vec3 w = ls::transform_point(in.object_to_world, p);
      if (glm::any(glm::lessThan(w, inst_boxes[k].lo)) || glm::any(glm::greaterThan(w, inst_boxes[k].hi))) ++outside;
    }
    CHECK(outside == 0);
  }
  // The top level is a tree over the instance records (with leaf size up to max_leaf_size).
  check_tree(a.top_nodes, 0, 0, uint32_t(a.top_nodes.size()), inst_boxes, 0, uint32_t(inst_boxes.size()), max_leaf_size);
  CHECK(a.bytes_total() == expected_bytes(a));
}

}  // namespace

TEST_CASE("accel: one mesh used by 64 instances", "[accel]") {
  ls::Scene scene = base_scene();
  scene.meshes.push_back(random_soup(500, 11, 1.0f, 0.1f, "soup"));
  for (int i = 0; i < 64; ++i) {
    const glm::vec3 t(float(i % 8) * 3.0f, float(i / 8) * 3.0f, 0.0f);
    scene.instances.push_back(
        instance(0, transform(t, 0.1f * float(i), glm::vec3(0.3f, 1.0f, 0.2f), glm::vec3(1.0f + 0.01f * float(i), 1.0f, 0.5f))));
  }
  ls::validate_scene(scene);

  const ls::Accel two = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  CHECK(two.objects == 1);
  CHECK(two.instance_count == 64);
  CHECK(two.tris.size() == 500);
  std::vector<Bounds> boxes;
  for (const glm::uvec3& t : scene.meshes[0].triangles) {
    Bounds b;
    b.grow(scene.meshes[0].positions[t.x]);
    b.grow(scene.meshes[0].positions[t.y]);
    b.grow(scene.meshes[0].positions[t.z]);
    boxes.push_back(b);
  }
  CHECK(two.nodes.size() == ls::build_bvh(boxes).nodes.size());
  check_two_level(scene, two);

  const ls::Accel flat = ls::build_accel(scene, ls::parse_structure("bvh"));
  CHECK(flat.objects == 1);
  CHECK(flat.tris.size() == 64 * 500);
  check_flat(scene, flat);
  // The flat structure over 64 copies is (much) larger than the two-level one.
  CHECK(flat.bytes_total() > 32 * (two.bytes_total() / 64));
}

TEST_CASE("accel: several meshes, some shared, one unused", "[accel]") {
  ls::Scene scene = base_scene();
  scene.meshes.push_back(random_soup(300, 21, 1.0f, 0.1f, "a"));
  scene.meshes.push_back(square_grid(10, 0.0f, 1.0f, "grid"));
  scene.meshes.push_back(random_soup(50, 22, 1.0f, 0.1f, "unused"));
  scene.meshes.push_back(random_soup(1, 23, 1.0f, 0.1f, "single"));
  scene.meshes.push_back(square_grid(1, 0.0f, 1.0f, "quad"));
  const std::vector<std::pair<uint32_t, glm::mat4>> placed = {
      {1, transform(glm::vec3(0.0f), 0.0f, glm::vec3(0, 0, 1), glm::vec3(1.0f))},
      {0, transform(glm::vec3(5, 0, 0), 0.7f, glm::vec3(1, 0, 0), glm::vec3(2.0f, 0.5f, 1.0f))},
      {3, transform(glm::vec3(0, 5, 0), 0.0f, glm::vec3(0, 0, 1), glm::vec3(1.0f))},
      {0, transform(glm::vec3(-5, 0, 0), 2.0f, glm::vec3(0, 1, 1), glm::vec3(-1.0f, 1.0f, 1.0f))},  // mirrored
      {4, transform(glm::vec3(0, 0, 5), 1.0f, glm::vec3(1, 1, 0), glm::vec3(3.0f))},
      {1, transform(glm::vec3(0, -5, 0), 0.3f, glm::vec3(0, 0, 1), glm::vec3(1.0f, 1.0f, -2.0f))},
  };
  for (const auto& [mesh, m] : placed) scene.instances.push_back(instance(mesh, m));
  ls::validate_scene(scene);

  const ls::Accel flat = ls::build_accel(scene, ls::parse_structure("f-bvh"));
  CHECK(flat.objects == 4);
  check_flat(scene, flat);
  const ls::Accel two = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  CHECK(two.objects == 4);
  check_two_level(scene, two);

  SECTION("other leaf sizes") {
    for (int leaf : {1, 2, 8}) {
      INFO("max_leaf_size " << leaf);
      BvhBuildOptions o;
      o.max_leaf_size = leaf;
      check_flat(scene, ls::build_accel(scene, ls::parse_structure("bvh"), o), leaf);
      check_two_level(scene, ls::build_accel(scene, ls::parse_structure("2l-bvh"), o), leaf);
    }
  }
}

TEST_CASE("accel: single triangle and single instance scenes", "[accel]") {
  ls::Scene scene = base_scene();
  scene.meshes.push_back(make_mesh({glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)}, {glm::uvec3(0, 1, 2)}, "tri"));
  scene.instances.push_back(instance(0, glm::mat4(1.0f)));
  ls::validate_scene(scene);
  const ls::Accel flat = ls::build_accel(scene, ls::parse_structure("bvh"));
  REQUIRE(flat.nodes.size() == 1);
  CHECK(flat.nodes[0].count == 1);
  CHECK(flat.max_depth == 0);
  check_flat(scene, flat);
  const ls::Accel two = ls::build_accel(scene, ls::parse_structure("2l-bvh"));
  REQUIRE(two.nodes.size() == 1);
  REQUIRE(two.top_nodes.size() == 1);
  CHECK(two.objects == 1);
  check_two_level(scene, two);
}

TEST_CASE("accel: large flat scene", "[accel]") {
  ls::Scene scene = base_scene();
  scene.meshes.push_back(random_soup(20000, 31, 1.0f, 0.1f, "big"));
  scene.meshes.push_back(square_grid(60, 0.0f, 1.0f, "grid"));
  scene.instances.push_back(instance(0, glm::mat4(1.0f)));
  scene.instances.push_back(instance(1, transform(glm::vec3(-0.5f, -0.5f, 0.0f), 0.0f, glm::vec3(0, 0, 1), glm::vec3(1.0f))));
  scene.instances.push_back(instance(0, transform(glm::vec3(0, 0, 3), 0.5f, glm::vec3(0, 1, 0), glm::vec3(0.5f))));
  ls::validate_scene(scene);
  check_flat(scene, ls::build_accel(scene, ls::parse_structure("bvh")));
  check_two_level(scene, ls::build_accel(scene, ls::parse_structure("2l-bvh")));
}
