#include "cpu/trace/exact_wide_bvh.h"

#include "common/base/huge_pages.h"
#include "common/base/parallel.h"

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
  const ExactLeaves leaves;
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
  // surface area heuristic prefers as one leaf (merge[b], see sah).
  std::vector<uint8_t> merge;
  // A Line Space node below the entry is a lane of its own; its merge[] belongs to its own entry.
  bool ls_node(uint32_t b) const { return !node_ls.empty() && node_ls[b] != lsk::LS_INVALID; }
  bool leaf_lane(uint32_t b) const { return ls_node(b) || !inner(b) || merge[b] != 0; }

  // The collapse of least expected cost, by the surface area heuristic (Ylitie, Karras and Laine,
  // "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, section
  // 3.1): cost[i - 1] of b is the least cost of b's subtree given as at most i lanes of its wide
  // parent, in half-area units with ExactWideTree's kNodeCost per wide node and leaf_cost per leaf
  // (its blocks of triangles, or its instances).  One lane is b itself, as a leaf or as a wide
  // node; more divide the lanes between b's two children.  split[b][i - 1], for i >= 2, is how many
  // of those i the first child gets, 0 where i - 1 lanes cost as little; split[b][0] is that
  // division for b's own wide node, kWidth lanes.  Marks merge[b].  In doubles: the half areas of
  // huge boxes overflow a float.
  using Costs = std::array<double, kWidth>;
  std::vector<std::array<uint8_t, kWidth>> split;

  // The top `parallel_levels` levels below b recurse as parallel tasks.
  Costs sah(uint32_t b, int parallel_levels = 0) {
    using Tree = ExactWideTree<kWidth>;
    const lsk::BvhNode& n = nodes[b];
    const double area = half_area(n);
    Costs cost;
    split[b].fill(0);
    if (!inner(b)) {
      prims[b] = n.count;
      cost.fill(area * Tree::leaf_cost(leaves, n.count));
      return cost;
    }
    Costs l;
    Costs r;
    // A Line Space child is a lane of its own; more than kLeafMax primitives keeps it out of a leaf.
    auto child = [&](uint32_t c, int levels, Costs& cost_c, uint32_t& prims_c) {
      if (ls_node(c)) {
        cost_c.fill(half_area(nodes[c]) * ExactWideTree<kWidth>::kLookupCost);
        prims_c = ExactWideTree<kWidth>::kLeafMax + 1u;
        return;
      }
      cost_c = sah(c, levels);
      prims_c = prims[c];
    };
    uint32_t prims_l = 0;
    uint32_t prims_r = 0;
    if (parallel_levels > 0)
      ls::parallel_invoke([&] { child(n.first, parallel_levels - 1, l, prims_l); },
                          [&] { child(n.first + 1, parallel_levels - 1, r, prims_r); });
    else {
      child(n.first, 0, l, prims_l);
      child(n.first + 1, 0, r, prims_r);
    }
    const uint32_t count = prims_l + prims_r;
    prims[b] = count;
    // j lanes divided between the children, k to the first: the cheapest k for each j.  k starts
    // at 1, so a cost that is not finite still leaves a valid division.
    std::array<double, kWidth + 1> divided;
    std::array<uint8_t, kWidth + 1> divided_k;
    for (int j = 2; j <= kWidth; ++j) {
      divided[size_t(j)] = l[0] + r[size_t(j - 2)];
      divided_k[size_t(j)] = 1;
      for (int k = 2; k < j; ++k) {
        const double c = l[size_t(k - 1)] + r[size_t(j - k - 1)];
        if (c < divided[size_t(j)]) {
          divided[size_t(j)] = c;
          divided_k[size_t(j)] = uint8_t(k);
        }
      }
    }
    const double as_node = area * Tree::kNodeCost + divided[kWidth];
    const double as_leaf =
        count <= Tree::kLeafMax ? area * Tree::leaf_cost(leaves, count) : std::numeric_limits<double>::infinity();
    merge[b] = as_leaf <= as_node;
    cost[0] = merge[b] ? as_leaf : as_node;
    split[b][0] = divided_k[kWidth];
    for (int i = 2; i <= kWidth; ++i) {
      const bool more = divided[size_t(i)] < cost[size_t(i - 2)];
      cost[size_t(i - 1)] = more ? divided[size_t(i)] : cost[size_t(i - 2)];
      split[b][size_t(i - 1)] = more ? divided_k[size_t(i)] : 0;
    }
    return cost;
  }
  std::vector<uint32_t> prims;  // per node below an entry: its primitives (sah)

  static double half_area(const lsk::BvhNode& n) {
    const double x = double(n.hi.x) - double(n.lo.x);
    const double y = double(n.hi.y) - double(n.lo.y);
    const double z = double(n.hi.z) - double(n.lo.z);
    return x * y + y * z + z * x;
  }

  // The lanes of the wide node for the inner node b, as sah chose them.
  int children(uint32_t b, std::array<uint32_t, kWidth>& lanes) const {
    int n = 0;
    auto emit = [&](auto&& self, uint32_t x, int i) -> void {  // x as at most i lanes, as split says
      if (ls_node(x)) i = 1;  // one lane, whatever more its parent's costs allowed (its split[] is its entry's)
      while (i > 1 && split[x][size_t(i - 1)] == 0) --i;
      if (i == 1) {
        lanes[size_t(n++)] = x;
        return;
      }
      const int k = split[x][size_t(i - 1)];
      self(self, nodes[x].first, k);
      self(self, nodes[x].first + 1, i - k);
    };
    const int k = split[b][0];
    emit(emit, nodes[b].first, k);
    emit(emit, nodes[b].first + 1, kWidth - k);
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
    for (int i = 0; i < kWidth; ++i) {  // unused lanes: a NaN box, which no ray enters (wide_tracer.h)
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
      if (ls_node(lanes[size_t(i)])) {
        w.child[i] = lanes[size_t(i)];
        w.count[i] = kLsLane;
      } else if (leaf_lane(lanes[size_t(i)])) {
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
                                       const std::vector<uint32_t>& roots, ExactLeaves leaves) {
  ExactWideTree<W> tree;
  tree.entry_of.assign(nodes.size(), lsk::LS_INVALID);
  Collapser<W> c{nodes, node_ls, leaves, tree, {}, {}, {}, {}};
  std::vector<uint32_t> entries;
  for (uint32_t r : roots)
    if (r != lsk::LS_INVALID && r < nodes.size() && c.inner(r)) entries.push_back(r);
  for (uint32_t b = 0; b < node_ls.size(); ++b)
    if (c.ls_node(b) && c.inner(b)) entries.push_back(b);
  c.merge.assign(nodes.size(), 0);
  c.split.resize(nodes.size());
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
                                                   const std::vector<uint32_t>&, ExactLeaves);
template ExactWideTree<8> build_exact_wide_tree<8>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                                   const std::vector<uint32_t>&, ExactLeaves);

}  // namespace ls
