// The wide BVH of the fast path's order-free walk: 4- or 8-wide nodes that hold only their children's
// boxes (SoA, 128 or 256 bytes a node, like Embree's), traversed nearest child first.  The width is
// AccelOptions::exact_width (--exact-width; 8 by default, docs/performance.md).
//
// Why it may ignore the reference's visiting order: a closest-hit query's answer does not depend on
// it (the smaller t wins, ties go to the lower (instance, triangle): common/kernels/hit.h), the box
// tests only prune (ray_box never prunes a box holding a hit that could still win), and a Line Space
// lookup's answer is a function of the ray and its node alone (common/kernels/ls_lookup.h).  So the
// walk in any order ends with the reference's hit, bit for bit.  What depends on the order — the
// triangle an any-hit query reports first, and the Line Space counters — is the reference's own.
//
// Entries: the walk starts at the *entry* nodes of a binary BVH: each root (the flat BVH's, each
// object's), and each inner Line Space node (its subtree, walked when a lookup is refused).  Each
// entry is collapsed on its own into the wide tree of least expected cost by the surface area
// heuristic (Ylitie, Karras and Laine 2017: a dynamic programme over the binary tree, which chooses
// for every wide node which binary descendants become its lanes, and which subtrees of at most
// kLeafMax primitives become one leaf: four triangles cost one SIMD test whether they sit in one
// binary leaf or in three, and a level less is a load less).  A Line Space node below an entry is a
// lane of its own (kLsLane), of cost kLookupCost.  The collapse replaced a greedy one (open the child
// of largest area while there is room), whose bottom levels were wide nodes of two or three leaves:
// on builtin:generated:143000:49:1, 14,618 nodes, 44 % of them with two lanes, against 8,736 now
// (docs/performance.md).
#pragma once

#include "common/kernels/layouts.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ls {

// What a tree's leaves hold, for the collapse's cost model: triangles, tested a block of four at a
// time, or instances (a two-level top level), each entered on its own (its ray transformed, its
// object's walk set up and begun).
enum class ExactLeaves { Triangles, Instances };

template <int W>
struct alignas(64) ExactWideNode {
  static constexpr int kWidth = W;
  float lo[3][kWidth];  // per axis, per child: its box (NaN in an unused lane)
  float hi[3][kWidth];
  uint32_t child[kWidth];  // inner: wide node; leaf: its first primitive (triangle trees: its first
                           // block lane, see triangle_blocks.h); Line Space lane: its binary node;
                           // unused lane: LS_INVALID
  uint32_t count[kWidth];  // leaf: primitive count; kLsLane: a Line Space node; 0: inner node or unused lane
};

// The count of a lane that is a Line Space node: looked up, and its subtree walked (the entry at its
// binary node) or its binary leaf tested when the lookup refuses.
constexpr uint32_t kLsLane = 0xFFFFFFFFu;
// A lane of primitives (not an inner node, unused, or a Line Space node).
inline bool primitive_lane(uint32_t count) { return count != 0u && count != kLsLane; }
static_assert(sizeof(ExactWideNode<4>) == 128, "two cache lines, like Embree's 4-wide node");
static_assert(sizeof(ExactWideNode<8>) == 256, "four cache lines, like Embree's 8-wide node");

// One collapsed BVH array (the flat BVH, all object BVHs of a 2L structure, or its top level).
template <int W>
struct ExactWideTree {
  using Node = ExactWideNode<W>;
  static constexpr uint32_t kLeafMax = 4;  // one triangle block
  // The collapse's cost model: a wide node's box tests, a block of four triangles, and an instance
  // entered, per ray that reaches their box.  The first two in the ratio of the fast path's
  // instructions (callgrind): about 110 a wide node visited, 280 a block; bvh's traversal time
  // hardly moved for block costs from 1.5 to 5, nor 2l-bvh's for instance costs from 1 to 16
  // (docs/performance.md).
  static constexpr double kNodeCost = 1.0;
  static constexpr double kBlockCost = 2.5;
  static constexpr double kInstanceCost = 4.0;
  // A Line Space lane: a lookup (a shaft, a candidate and its plane: about three nodes' work, an
  // estimate) and the subtree's walk when refused.  It only shapes the levels above the lane.
  static constexpr double kLookupCost = 3.0;
  // The cost of a leaf of `count` primitives, per ray that reaches its box.
  static double leaf_cost(ExactLeaves leaves, uint32_t count) {
    return leaves == ExactLeaves::Triangles ? kBlockCost * double((count + 3u) / 4u) : kInstanceCost * double(count);
  }
  std::vector<Node> nodes;
  std::vector<uint32_t> entry_of;  // per binary node: the wide node of the entry rooted there, or LS_INVALID
  size_t entries = 0;
  size_t bytes() const { return nodes.size() * sizeof(Node) + entry_of.size() * sizeof(uint32_t); }
};

// Collapses the entries of each of `roots` into W-wide nodes (W = 4 or 8).  node_ls may be empty
// (no Line Space); Line Space nodes must not nest.
template <int W>
ExactWideTree<W> build_exact_wide_tree(const std::vector<lsk::BvhNode>& nodes, const std::vector<uint32_t>& node_ls,
                                       const std::vector<uint32_t>& roots, ExactLeaves leaves = ExactLeaves::Triangles);

}  // namespace ls
