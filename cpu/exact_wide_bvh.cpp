#include "exact_wide_bvh.h"

#include "huge_pages.h"
#include "parallel.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>

namespace ls {
namespace {

template <int kWidth>
struct Collapser {
  const std::vector<lsk::BvhNode>& nodes;
  const std::vector<uint32_t>& node_ls;
  ExactWideTree<kWidth>& tree;

  bool inner(uint32_t b) const { return nodes[b].count == 0; }

  // The primitives of b's subtree: one contiguous range (the builder's order).
  struct Range {
    uint32_t first;
    uint32_t count;
  };
  Range range(uint32_t b) const {
    if (!inner(b)) return Range{nodes[b].first, nodes[b].count};
    const Range l = range(nodes[b].first);
    const Range r = range(nodes[b].first + 1);
    return Range{std::min(l.first, r.first), l.count + r.count};
  }
  // A lane for b is a leaf: a binary leaf, or a subtree of at most kLeafMax primitives that the
  // surface area heuristic prefers as one leaf (merge[b], see sah_cost).
  std::vector<uint8_t> merge;
  bool leaf_lane(uint32_t b) const { return !inner(b) || merge[b] != 0; }

  // The expected cost of a ray that reaches b's box, in box tests (SAH), with b's subtree made a
  // leaf wherever that is cheaper, and the primitives below b.  Marks merge[b].
  struct Sah {
    float cost;
    uint32_t count;
  };
  // The top `parallel_levels` levels below b recurse as parallel tasks.
  Sah sah(uint32_t b, int parallel_levels = 0) {
    const lsk::BvhNode& n = nodes[b];
    if (!inner(b)) {
      prims[b] = n.count;
      return Sah{kBlockCost * float((n.count + 3u) / 4u), n.count};
    }
    Sah l;
    Sah r;
    if (parallel_levels > 0)
      ls::parallel_invoke([&] { l = sah(n.first, parallel_levels - 1); }, [&] { r = sah(n.first + 1, parallel_levels - 1); });
    else {
      l = sah(n.first);
      r = sah(n.first + 1);
    }
    const float area = half_area(n);
    const float split = area > 0.0f
                            ? 1.0f + (half_area(nodes[n.first]) * l.cost + half_area(nodes[n.first + 1]) * r.cost) / area
                            : 1.0f + l.cost + r.cost;
    const uint32_t count = l.count + r.count;
    prims[b] = count;
    if (count <= ExactWideTree<kWidth>::kLeafMax && kBlockCost <= split) {
      merge[b] = 1;
      return Sah{kBlockCost, count};
    }
    return Sah{split, count};
  }
  std::vector<uint32_t> prims;  // per node below an entry: its primitives (sah)

  // A block of four triangles costs about four box tests (the ratio of their instruction counts in
  // the fast path, callgrind); a node's box test is the unit.
  static constexpr float kBlockCost = 4.0f;

  std::vector<uint8_t> has_ls;  // per node: 1 when a Line Space node lies in its subtree (itself included)

  bool holds_ls(uint32_t b) const { return !has_ls.empty() && has_ls[b] != 0; }

  void mark_ls(uint32_t b) {
    if (inner(b)) {
      mark_ls(nodes[b].first);
      mark_ls(nodes[b].first + 1);
    }
    has_ls[b] = node_ls[b] != lsk::LS_INVALID || (inner(b) && (has_ls[nodes[b].first] || has_ls[nodes[b].first + 1]));
  }

  // The entries below b: b itself when nothing strictly below it carries a Line Space.
  void find_entries(uint32_t b, std::vector<uint32_t>& out) const {
    if (!inner(b)) return;
    const uint32_t l = nodes[b].first;
    if (!holds_ls(l) && !holds_ls(l + 1)) {
      out.push_back(b);
      return;
    }
    find_entries(l, out);
    find_entries(l + 1, out);
  }

  static float half_area(const lsk::BvhNode& n) {
    const lsk::vec3 d = n.hi - n.lo;
    return d.x * d.y + d.y * d.z + d.z * d.x;
  }

  // The children of the wide node for the inner node b: its two children, then, while fewer than
  // kWidth, the inner child of largest surface area replaced by its two children.
  int children(uint32_t b, std::array<uint32_t, kWidth>& lanes) const {
    std::array<float, kWidth> area;  // an inner lane's half area, -1 for a leaf lane (never opened)
    auto set = [&](int i, uint32_t node) {
      lanes[size_t(i)] = node;
      area[size_t(i)] = leaf_lane(node) ? -1.0f : half_area(nodes[node]);
    };
    set(0, nodes[b].first);
    set(1, nodes[b].first + 1);
    int n = 2;
    while (n < kWidth) {
      int best = -1;
      float best_area = -1.0f;
      for (int i = 0; i < n; ++i)
        if (area[size_t(i)] > best_area) {
          best = i;
          best_area = area[size_t(i)];
        }
      if (best < 0) break;
      const uint32_t opened = lanes[size_t(best)];
      set(best, nodes[opened].first);
      set(n++, nodes[opened].first + 1);
    }
    return n;
  }

  // Runs body(i) for i in [0, n): in parallel when the subtree below b is large enough to pay for
  // the tasks (a task per lane; lanes are disjoint subtrees, each written by one task).
  template <class Body>
  void for_lanes(uint32_t b, int n, Body&& body) const {
    if (prims[b] > kParallelPrims)
      ls::parallel_for(0, n, body);
    else
      for (int i = 0; i < n; ++i) body(i);
  }
  static constexpr uint32_t kParallelPrims = 4096;

  std::vector<uint32_t> wide_nodes;  // per node that becomes a wide node: the wide nodes of its subtree

  // The wide nodes of b's collapsed subtree, kept in wide_nodes[] for collapse's layout.
  uint32_t count(uint32_t b) {
    std::array<uint32_t, kWidth> lanes;
    const int n = children(b, lanes);
    std::array<uint32_t, kWidth> below{};
    for_lanes(b, n, [&](int i) {
      if (!leaf_lane(lanes[size_t(i)])) below[size_t(i)] = count(lanes[size_t(i)]);
    });
    uint32_t total = 1;
    for (int i = 0; i < n; ++i) total += below[size_t(i)];
    wide_nodes[b] = total;
    return total;
  }

  // Writes b's wide node at `index` and its subtree after it, depth first (a node, then its
  // children's subtrees in lane order): where each subtree lands is known from wide_nodes[], so
  // large subtrees are written in parallel, and the layout is the serial walk's whatever the schedule.
  void collapse(uint32_t b, uint32_t index) {
    std::array<uint32_t, kWidth> lanes;
    const int n = children(b, lanes);
    ExactWideNode<kWidth>& w = tree.nodes[index];
    std::memset(&w, 0, sizeof(w));
    for (int i = 0; i < kWidth; ++i) {  // unused lanes: a NaN box, which no ray enters (fast_tracer.cpp)
      w.child[i] = lsk::LS_INVALID;
      for (int a = 0; a < 3; ++a) w.lo[a][i] = w.hi[a][i] = std::numeric_limits<float>::quiet_NaN();
    }
    uint32_t next = index + 1;
    for (int i = 0; i < n; ++i) {
      const lsk::BvhNode& c = nodes[lanes[size_t(i)]];
      for (int a = 0; a < 3; ++a) {
        w.lo[a][i] = c.lo[a];
        w.hi[a][i] = c.hi[a];
      }
      if (leaf_lane(lanes[size_t(i)])) {
        const Range r = range(lanes[size_t(i)]);
        w.child[i] = r.first;
        w.count[i] = r.count;
      } else {
        w.child[i] = next;
        next += wide_nodes[lanes[size_t(i)]];
      }
    }
    for_lanes(b, n, [&](int i) {
      if (!leaf_lane(lanes[size_t(i)])) collapse(lanes[size_t(i)], w.child[i]);
    });
  }
};

}  // namespace

template <int W>
ExactWideTree<W> build_exact_wide_tree(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                                       const std::vector<uint32_t>& roots) {
  ExactWideTree<W> tree;
  tree.entry_of.assign(nodes.size(), lsk::LS_INVALID);
  Collapser<W> c{nodes, node_ls, tree, {}, {}, {}, {}};
  std::vector<uint32_t> entries;
  if (!node_ls.empty()) {
    c.has_ls.assign(nodes.size(), 0);
    for (uint32_t r : roots)
      if (r != lsk::LS_INVALID && r < nodes.size()) c.mark_ls(r);
  }
  for (uint32_t r : roots)
    if (r != lsk::LS_INVALID && r < nodes.size()) c.find_entries(r, entries);
  c.merge.assign(nodes.size(), 0);
  c.prims.resize(nodes.size());
  c.wide_nodes.resize(nodes.size());
  // Each entry once (two-level roots may share one), in order; entries are disjoint subtrees.
  std::vector<uint32_t> unique;
  for (uint32_t e : entries)
    if (tree.entry_of[e] == lsk::LS_INVALID) {
      tree.entry_of[e] = 0;  // marks it seen; its index is set below
      unique.push_back(e);
    }
  // Entries are the tasks; where there are few (a flat structure has one), the top of each one's
  // SAH is split into tasks too (count and collapse split large subtrees themselves).
  const int parallel_levels = unique.size() < 8 ? 5 : 0;
  ls::parallel_for(size_t(0), unique.size(), [&](size_t k) {
    c.sah(unique[k], parallel_levels);
    c.count(unique[k]);
  });
  size_t total = 0;
  for (uint32_t e : unique) {
    tree.entry_of[e] = uint32_t(total);
    total += c.wide_nodes[e];
  }
  resize_huge(tree.nodes, total);
  ls::parallel_for(size_t(0), unique.size(), [&](size_t k) { c.collapse(unique[k], tree.entry_of[unique[k]]); });
  tree.entries = unique.size();
  return tree;
}

template ExactWideTree<4> build_exact_wide_tree<4>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                                   const std::vector<uint32_t>&);
template ExactWideTree<8> build_exact_wide_tree<8>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                                   const std::vector<uint32_t>&);

}  // namespace ls
