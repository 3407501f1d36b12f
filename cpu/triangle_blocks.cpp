#include "triangle_blocks.h"

#include "huge_pages.h"
#include "parallel.h"

namespace ls {

TriangleBlocks build_triangle_blocks(const std::vector<lsk::BvhNode>& nodes, const std::vector<lsk::Triangle>& tris) {
  TriangleBlocks out;
  out.block_of.assign(nodes.size(), lsk::LS_INVALID);
  size_t total = 0;  // offsets first, then the blocks filled in parallel
  for (size_t n = 0; n < nodes.size(); ++n)
    if (nodes[n].count > 0) {
      out.block_of[n] = uint32_t(total);
      total += (nodes[n].count + 3u) / 4u;
    }
  resize_huge(out.blocks, total);  // zeros: vertices past a leaf's count stay 0
  ls::parallel_for(size_t(0), nodes.size(), [&](size_t n) {
    const lsk::BvhNode& node = nodes[n];
    for (uint32_t k = 0; k < (node.count + 3u) / 4u * 4u; ++k) {
      TriBlock& block = out.blocks[out.block_of[n] + k / 4u];
      if (k >= node.count) {
        block.prim[k % 4u] = lsk::LS_INVALID;
        continue;
      }
      const lsk::Triangle& t = tris[node.first + k];
      const glm::vec4* v[3] = {&t.v0, &t.v1, &t.v2};
      for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) block.v[i][a][k % 4u] = (*v[i])[a];
      block.prim[k % 4u] = node.first + k;
    }
  });
  return out;
}

}  // namespace ls
