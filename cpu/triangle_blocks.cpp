#include "triangle_blocks.h"

#include "exact_wide_bvh.h"
#include "huge_pages.h"
#include "parallel.h"

namespace ls {

template <int W>
TriangleBlocks build_triangle_blocks(const std::vector<lsk::BvhNode>& nodes, const std::vector<lsk::Triangle>& tris,
                                     ExactWideTree<W>& exact) {
  struct Range {
    uint32_t first;
    uint32_t count;
  };
  std::vector<Range> ranges;  // each gets blocks of its own, lanes past its end unused
  std::vector<uint32_t*> exact_children;
  for (ExactWideNode<W>& node : exact.nodes)
    for (int l = 0; l < W; ++l)
      if (node.count[l] > 0) {
        ranges.push_back(Range{node.child[l], node.count[l]});
        exact_children.push_back(&node.child[l]);
      }
  // The lane of every triangle inside an exact leaf, then the binary leaves outside them.
  std::vector<uint32_t> lane_of_tri(tris.size(), lsk::LS_INVALID);
  size_t lanes = 0;
  for (size_t r = 0; r < ranges.size(); ++r) {
    *exact_children[r] = uint32_t(lanes);
    for (uint32_t k = 0; k < ranges[r].count; ++k) lane_of_tri[ranges[r].first + k] = uint32_t(lanes + k);
    lanes += (ranges[r].count + 3u) / 4u * 4u;
  }
  for (const lsk::BvhNode& n : nodes)
    if (n.count > 0 && lane_of_tri[n.first] == lsk::LS_INVALID) {
      ranges.push_back(Range{n.first, n.count});
      for (uint32_t k = 0; k < n.count; ++k) lane_of_tri[n.first + k] = uint32_t(lanes + k);
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
    // The range's blocks are its own (its first lane is a multiple of 4): their normals four at a
    // time, which took half of this function's time one by one.
    const uint32_t first = lane_of_tri[ranges[r].first] / 4u;
    for (uint32_t b = first; b < first + (ranges[r].count + 3u) / 4u; ++b) block_lanes::plane_normals(out.blocks[b]);
  });
  return out;
}

template TriangleBlocks build_triangle_blocks<4>(const std::vector<lsk::BvhNode>&, const std::vector<lsk::Triangle>&,
                                                 ExactWideTree<4>&);
template TriangleBlocks build_triangle_blocks<8>(const std::vector<lsk::BvhNode>&, const std::vector<lsk::Triangle>&,
                                                 ExactWideTree<8>&);

}  // namespace ls
