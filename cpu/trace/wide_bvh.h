// The wide BVH of the fast CPU path: the binary BVH of an Accel collapsed into treelets of K levels
// (K = 2: 4 grandchildren per node, a 4-wide BVH; K = 3: 8-wide), the boxes of every treelet node in
// SoA layout so that one SIMD pass tests them all.
//
// Why treelets that keep their inner boxes, rather than boxes of the 2^K frontier children only: the
// fast path must give the reference's answers bit for bit, Line Space decisions and counters
// included.  An LS lookup's answer depends on the current hit distance (a plane hit beyond it is
// refused), so the reference's *visiting order* is part of the result.  Keeping the intermediate
// boxes lets the wide traversal make exactly the reference's decisions (nearer child first, the same
// box tests against the same current t), while the box arithmetic runs K levels at a time in SIMD and
// a node's boxes sit in a few adjacent cache lines.  A Line Space node is the treelet position of its
// BVH node: a wide node's child at its integration depth.
//
// Positions inside a treelet are numbered like a heap: 1 is the treelet's root (a binary inner
// node), the children of p are 2p and 2p + 1; positions 2 .. 2^(K+1) - 1 have a lane each
// (lane = position - 2).  A lane at the bottom level whose node is an inner node continues in the
// wide node `first[lane]` (that node's treelet root).
#pragma once

#include "common/kernels/layouts.h"
#include "common/structure/accel.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ls {

struct Accel;

template <int K>
struct alignas(64) WideNode {
  static constexpr int kLanes = (1 << (K + 1)) - 2;        // positions 2 .. 2^(K+1) - 1
  static constexpr int kPadded = kLanes <= 8 ? 8 : 16;     // whole SIMD batches (4 or 8 floats)
  static constexpr uint32_t kBottom = 1u << K;             // first position of the bottom level
  float lo[3][kPadded];     // per axis, per lane: the node's box (unused lanes hold 0)
  float hi[3][kPadded];
  uint32_t first[kLanes];   // leaf: first triangle / instance; bottom-level inner node: its wide node
  uint32_t count[kLanes];   // leaf: primitive count; 0: inner node (or an unused lane)
  uint32_t ls[kLanes];      // the node's LsNode, or LS_INVALID
  uint32_t tri_lane[kLanes];  // triangle leaf: the lane index of its first triangle (triangle_blocks.h)
  uint32_t exact[kLanes];   // inner node: the order-free walk's entry rooted there (exact_wide_bvh.h)
  uint32_t root_ls;         // the treelet root's LsNode, or LS_INVALID
  uint32_t root_exact;      // the treelet root's entry, or LS_INVALID
};

// One collapsed BVH array (the flat BVH, all object BVHs of a 2L structure, or its top level).
template <int K>
struct WideTree {
  std::vector<WideNode<K>> nodes;
  std::vector<uint32_t> wide_of;  // per binary node: the wide node rooted there, or LS_INVALID
  size_t bytes() const { return nodes.size() * sizeof(WideNode<K>) + wide_of.size() * sizeof(uint32_t); }
};

// Collapses `nodes` below each of `roots`.  Per binary node, each of these may be empty (none): node_ls
// (its LsNode), lane_of (a leaf's first triangle lane), entry_of (the exact wide tree's entry).
template <int K>
WideTree<K> build_wide_tree(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                            const std::vector<uint32_t>& roots, const std::vector<uint32_t>& lane_of,
                            const std::vector<uint32_t>& entry_of);

}  // namespace ls
