#include "exact_wide_bvh.h"

#include "huge_pages.h"

#include <array>
#include <cstring>

namespace ls {
namespace {

constexpr int kWidth = ExactWideNode::kWidth;

struct Collapser {
  const std::vector<lsk::BvhNode>& nodes;
  const std::vector<uint32_t>& node_ls;
  const std::vector<uint32_t>& leaf_ref;
  ExactWideTree& tree;

  bool inner(uint32_t b) const { return nodes[b].count == 0; }

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
        if (inner(lanes[size_t(i)]) && half_area(nodes[lanes[size_t(i)]]) > best_area) {
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
      if (inner(lanes[size_t(i)])) total += count(lanes[size_t(i)]);
    return total;
  }

  uint32_t collapse(uint32_t b) {
    std::array<uint32_t, kWidth> lanes;
    const int n = children(b, lanes);
    const uint32_t index = uint32_t(tree.nodes.size());
    ExactWideNode w;
    std::memset(&w, 0, sizeof(w));
    for (int i = 0; i < kWidth; ++i) w.child[i] = lsk::LS_INVALID;
    for (int i = 0; i < n; ++i) {
      const lsk::BvhNode& c = nodes[lanes[size_t(i)]];
      for (int a = 0; a < 3; ++a) {
        w.lo[a][i] = c.lo[a];
        w.hi[a][i] = c.hi[a];
      }
      if (c.count > 0) {
        w.child[i] = leaf_ref.empty() ? c.first : leaf_ref[lanes[size_t(i)]];
        w.count[i] = c.count;
      }
    }
    tree.nodes.push_back(w);
    for (int i = 0; i < n; ++i)
      if (inner(lanes[size_t(i)])) {
        const uint32_t child = collapse(lanes[size_t(i)]);
        tree.nodes[index].child[i] = child;
      }
    return index;
  }
};

}  // namespace

ExactWideTree build_exact_wide_tree(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                                    const std::vector<uint32_t>& roots, const std::vector<uint32_t>& leaf_ref) {
  ExactWideTree tree;
  tree.entry_of.assign(nodes.size(), lsk::LS_INVALID);
  Collapser c{nodes, node_ls, leaf_ref, tree, {}};
  std::vector<uint32_t> entries;
  if (!node_ls.empty()) {
    c.has_ls.assign(nodes.size(), 0);
    for (uint32_t r : roots)
      if (r != lsk::LS_INVALID && r < nodes.size()) c.mark_ls(r);
  }
  for (uint32_t r : roots)
    if (r != lsk::LS_INVALID && r < nodes.size()) c.find_entries(r, entries);
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

}  // namespace ls
