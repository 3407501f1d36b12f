#include "exact_wide_bvh.h"

#include "huge_pages.h"

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
  Sah sah(uint32_t b) {
    const lsk::BvhNode& n = nodes[b];
    if (!inner(b)) return Sah{kBlockCost * float((n.count + 3u) / 4u), n.count};
    const Sah l = sah(n.first);
    const Sah r = sah(n.first + 1);
    const float area = half_area(n);
    const float split = area > 0.0f
                            ? 1.0f + (half_area(nodes[n.first]) * l.cost + half_area(nodes[n.first + 1]) * r.cost) / area
                            : 1.0f + l.cost + r.cost;
    const uint32_t count = l.count + r.count;
    if (count <= ExactWideTree<kWidth>::kLeafMax && kBlockCost <= split) {
      merge[b] = 1;
      return Sah{kBlockCost, count};
    }
    return Sah{split, count};
  }
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
    lanes[0] = nodes[b].first;
    lanes[1] = nodes[b].first + 1;
    int n = 2;
    while (n < kWidth) {
      int best = -1;
      float best_area = -1.0f;
      for (int i = 0; i < n; ++i)
        if (!leaf_lane(lanes[size_t(i)]) && half_area(nodes[lanes[size_t(i)]]) > best_area) {
          best = i;
          best_area = half_area(nodes[lanes[size_t(i)]]);
        }
      if (best < 0) break;
      const uint32_t opened = lanes[size_t(best)];
      lanes[size_t(best)] = nodes[opened].first;
      lanes[size_t(n++)] = nodes[opened].first + 1;
    }
    return n;
  }

  size_t count(uint32_t b) const {
    std::array<uint32_t, kWidth> lanes;
    const int n = children(b, lanes);
    size_t total = 1;
    for (int i = 0; i < n; ++i)
      if (!leaf_lane(lanes[size_t(i)])) total += count(lanes[size_t(i)]);
    return total;
  }

  uint32_t collapse(uint32_t b) {
    std::array<uint32_t, kWidth> lanes;
    const int n = children(b, lanes);
    const uint32_t index = uint32_t(tree.nodes.size());
    ExactWideNode<kWidth> w;
    std::memset(&w, 0, sizeof(w));
    for (int i = 0; i < kWidth; ++i) {  // unused lanes: a NaN box, which no ray enters (fast_tracer.cpp)
      w.child[i] = lsk::LS_INVALID;
      for (int a = 0; a < 3; ++a) w.lo[a][i] = w.hi[a][i] = std::numeric_limits<float>::quiet_NaN();
    }
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
      }
    }
    tree.nodes.push_back(w);
    for (int i = 0; i < n; ++i)
      if (!leaf_lane(lanes[size_t(i)])) {
        const uint32_t child = collapse(lanes[size_t(i)]);
        tree.nodes[index].child[i] = child;
      }
    return index;
  }
};

}  // namespace

template <int W>
ExactWideTree<W> build_exact_wide_tree(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                                       const std::vector<uint32_t>& roots) {
  ExactWideTree<W> tree;
  tree.entry_of.assign(nodes.size(), lsk::LS_INVALID);
  Collapser<W> c{nodes, node_ls, tree, {}, {}};
  std::vector<uint32_t> entries;
  if (!node_ls.empty()) {
    c.has_ls.assign(nodes.size(), 0);
    for (uint32_t r : roots)
      if (r != lsk::LS_INVALID && r < nodes.size()) c.mark_ls(r);
  }
  for (uint32_t r : roots)
    if (r != lsk::LS_INVALID && r < nodes.size()) c.find_entries(r, entries);
  c.merge.assign(nodes.size(), 0);
  for (uint32_t e : entries) c.sah(e);
  size_t total = 0;
  for (uint32_t e : entries) total += c.count(e);  // an upper bound: roots shared by several count again
  reserve_huge(tree.nodes, total);
  for (uint32_t e : entries)
    if (tree.entry_of[e] == lsk::LS_INVALID) {
      tree.entry_of[e] = c.collapse(e);
      ++tree.entries;
    }
  return tree;
}

template ExactWideTree<4> build_exact_wide_tree<4>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                                   const std::vector<uint32_t>&);
template ExactWideTree<8> build_exact_wide_tree<8>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                                   const std::vector<uint32_t>&);

}  // namespace ls
