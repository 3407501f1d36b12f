#include "cpu/trace/triangle_blocks.h"

#include "common/base/huge_pages.h"
#include "common/base/parallel.h"
#include "cpu/trace/exact_wide_bvh.h"

#include <algorithm>
#include <array>

namespace ls {

template <int W>
TriangleBlocks build_triangle_blocks(const std::vector<lsk::BvhNode>& nodes, const std::vector<lsk::Triangle>& tris,
                                     ExactWideTree<W>& exact) {
  struct Range {
    uint32_t first;
    uint32_t count;
  };
  std::vector<Range> ranges;
  std::vector<uint32_t> lane_of_tri(tris.size(), lsk::LS_INVALID);
  size_t lanes = 0;  // lanes placed so far; blocks are lanes / 4
  auto place = [&](const Range& range, size_t first_lane) {
    for (uint32_t k = 0; k < range.count; ++k) lane_of_tri[range.first + k] = uint32_t(first_lane + k);
    ranges.push_back(range);
  };
  // The leaves of each exact wide node share its blocks: those of at most four triangles packed
  // first fit, largest first, so none straddles two blocks; a longer one takes blocks of its own.
  for (ExactWideNode<W>& node : exact.nodes) {
    std::array<int, W> order;
    int leaves = 0;
    for (int l = 0; l < W; ++l)
      if (primitive_lane(node.count[l])) order[size_t(leaves++)] = l;
    std::stable_sort(order.begin(), order.begin() + leaves, [&](int a, int b) { return node.count[a] > node.count[b]; });
    std::array<size_t, W> opened_block{};  // the blocks opened for this node's short leaves
    std::array<uint32_t, W> used{};        // and the lanes taken in each
    size_t opened = 0;
    for (int k = 0; k < leaves; ++k) {
      uint32_t& child = node.child[order[size_t(k)]];
      const Range range{child, node.count[order[size_t(k)]]};
      size_t lane;
      if (range.count > 4u) {
        lane = lanes;
        lanes += (range.count + 3u) / 4u * 4u;
      } else {
        size_t b = 0;
        while (b < opened && used[b] + range.count > 4u) ++b;
        if (b == opened) {
          opened_block[opened] = lanes / 4u;
          used[opened++] = 0;
          lanes += 4u;
        }
        lane = opened_block[b] * 4u + used[b];
        used[b] += range.count;
      }
      child = uint32_t(lane);
      place(range, lane);
    }
  }
  for (const lsk::BvhNode& n : nodes)  // the binary leaves outside them (Line Space nodes' own)
    if (n.count > 0 && lane_of_tri[n.first] == lsk::LS_INVALID) {
      place(Range{n.first, n.count}, lanes);
      lanes += (n.count + 3u) / 4u * 4u;
    }
  TriangleBlocks out;
  resize_huge(out.lane_of, nodes.size());
  ls::parallel_for(size_t(0), nodes.size(), [&](size_t n) {
    out.lane_of[n] = nodes[n].count > 0 ? lane_of_tri[nodes[n].first] : lsk::LS_INVALID;
  });
  resize_huge(out.blocks, lanes / 4u);  // zeros: vertices of unused lanes stay 0
  ls::parallel_for(size_t(0), out.blocks.size(), [&](size_t b) {
    for (uint32_t l = 0; l < 4u; ++l) out.blocks[b].prim[l] = lsk::LS_INVALID;
  });
  ls::parallel_for(size_t(0), ranges.size(), [&](size_t r) {
    for (uint32_t k = 0; k < ranges[r].count; ++k) {
      const uint32_t i = ranges[r].first + k;
      const uint32_t lane = lane_of_tri[i];
      TriBlock& block = out.blocks[lane / 4u];
      const glm::vec4* v[3] = {&tris[i].v0, &tris[i].v1, &tris[i].v2};
      for (int p = 0; p < 3; ++p)
        for (int a = 0; a < 3; ++a) block.v[p][a][lane % 4u] = (*v[p])[a];
      block.prim[lane % 4u] = i;
    }
  });
  // The normals four at a time, which took half of this function's time one by one.
  ls::parallel_for(size_t(0), out.blocks.size(), [&](size_t b) { block_lanes::plane_normals(out.blocks[b]); });
  return out;
}

template TriangleBlocks build_triangle_blocks<4>(const std::vector<lsk::BvhNode>&, const std::vector<lsk::Triangle>&,
                                                 ExactWideTree<4>&);
template TriangleBlocks build_triangle_blocks<8>(const std::vector<lsk::BvhNode>&, const std::vector<lsk::Triangle>&,
                                                 ExactWideTree<8>&);

}  // namespace ls
