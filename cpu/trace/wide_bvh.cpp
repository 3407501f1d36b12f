#include "cpu/trace/wide_bvh.h"

#include "common/base/huge_pages.h"

#include <array>
#include <cstring>

namespace ls {
namespace {

template <int K>
struct Collapser {
  const std::vector<lsk::BvhNode>& nodes;
  const std::vector<uint32_t>& node_ls;
  const std::vector<uint32_t>& lane_of;
  const std::vector<uint32_t>& entry_of;
  WideTree<K>& tree;

  static uint32_t of(const std::vector<uint32_t>& per_node, uint32_t b) {
    return per_node.empty() ? lsk::LS_INVALID : per_node[b];
  }
  uint32_t ls_of(uint32_t b) const { return of(node_ls, b); }

  static constexpr int kPositions = 1 << (K + 1);

  // The binary node at each treelet position below the inner node b (heap numbering, 1 = b), or
  // LS_INVALID where the node above is a leaf or missing.
  std::array<uint32_t, kPositions> positions(uint32_t b) const {
    std::array<uint32_t, kPositions> at;
    at.fill(lsk::LS_INVALID);
    at[1] = b;
    for (int p = 2; p < kPositions; ++p) {
      const uint32_t parent = at[size_t(p / 2)];
      if (parent != lsk::LS_INVALID && nodes[parent].count == 0) at[size_t(p)] = nodes[parent].first + uint32_t(p & 1);
    }
    return at;
  }
  // A bottom-level position holding an inner node: the treelet continues in a wide node of its own.
  bool continues(const std::array<uint32_t, kPositions>& at, int p) const {
    return at[size_t(p)] != lsk::LS_INVALID && nodes[at[size_t(p)]].count == 0;
  }

  // How many wide nodes collapse(b) makes (the vector is reserved once instead of growing by copies
  // of 320-byte nodes).
  size_t count(uint32_t b) const {
    const std::array<uint32_t, kPositions> at = positions(b);
    size_t total = 1;
    for (int p = int(WideNode<K>::kBottom); p < kPositions; ++p)
      if (continues(at, p)) total += count(at[size_t(p)]);
    return total;
  }

  // The treelet rooted at the binary inner node b, and (depth first) the treelets below it.
  uint32_t collapse(uint32_t b) {
    const uint32_t index = uint32_t(tree.nodes.size());
    tree.wide_of[b] = index;
    WideNode<K> w;
    std::memset(&w, 0, sizeof(w));
    w.root_ls = ls_of(b);
    w.root_exact = of(entry_of, b);
    const std::array<uint32_t, kPositions> at = positions(b);
    for (int p = 2; p < kPositions; ++p) {
      const uint32_t c = at[size_t(p)];
      if (c == lsk::LS_INVALID) continue;
      const int lane = p - 2;
      const lsk::BvhNode& n = nodes[c];
      for (int a = 0; a < 3; ++a) {
        w.lo[a][lane] = n.lo[a];
        w.hi[a][lane] = n.hi[a];
      }
      w.count[lane] = n.count;
      w.first[lane] = n.count > 0 ? n.first : 0u;
      w.ls[lane] = ls_of(c);
      w.tri_lane[lane] = n.count > 0 ? of(lane_of, c) : lsk::LS_INVALID;
      w.exact[lane] = n.count > 0 ? lsk::LS_INVALID : of(entry_of, c);
    }
    tree.nodes.push_back(w);
    for (int p = int(WideNode<K>::kBottom); p < kPositions; ++p)
      if (continues(at, p)) {
        const uint32_t child = collapse(at[size_t(p)]);
        tree.nodes[index].first[p - 2] = child;
      }
    return index;
  }
};

}  // namespace

template <int K>
WideTree<K> build_wide_tree(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                            const std::vector<uint32_t>& roots, const std::vector<uint32_t>& lane_of,
                            const std::vector<uint32_t>& entry_of) {
  WideTree<K> tree;
  tree.wide_of.assign(nodes.size(), lsk::LS_INVALID);
  Collapser<K> c{nodes, node_ls, lane_of, entry_of, tree};
  auto collapsible = [&](uint32_t r) { return r != lsk::LS_INVALID && r < nodes.size() && nodes[r].count == 0; };
  size_t total = 0;
  for (uint32_t r : roots)
    if (collapsible(r)) total += c.count(r);  // an upper bound: roots shared by several are counted again
  reserve_huge(tree.nodes, total);
  for (uint32_t r : roots)
    if (collapsible(r) && tree.wide_of[r] == lsk::LS_INVALID)
      c.collapse(r);
  return tree;
}

template WideTree<2> build_wide_tree<2>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                        const std::vector<uint32_t>&, const std::vector<uint32_t>&,
                                        const std::vector<uint32_t>&);
template WideTree<3> build_wide_tree<3>(const std::vector<lsk::BvhNode>&, const std::vector<uint32_t>&,
                                        const std::vector<uint32_t>&, const std::vector<uint32_t>&,
                                        const std::vector<uint32_t>&);

}  // namespace ls
