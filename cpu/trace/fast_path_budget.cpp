#include "cpu/trace/fast_path_budget.h"

#include "common/base/memory_budget.h"
#include "common/structure/accel.h"
#include "cpu/trace/exact_wide_bvh.h"
#include "cpu/trace/triangle_blocks.h"

#include <vector>

namespace ls {
namespace {

// What fast_path_bytes_at_most needs of one binary BVH array.
struct BvhShape {
  size_t nodes = 0;
  size_t inner = 0;
  size_t blocks = 0;  // ceil(count / 4) summed over the leaves
};

BvhShape bvh_shape(const std::vector<lsk::BvhNode>& nodes) {
  BvhShape s;
  s.nodes = nodes.size();
  for (const lsk::BvhNode& n : nodes)
    if (n.count > 0)
      s.blocks += (size_t(n.count) + 3u) / 4u;
    else
      ++s.inner;
  return s;
}

}  // namespace

size_t fast_path_bytes_at_most(const Accel& accel, int exact_width) {
  const size_t exact_node = exact_width == 8 ? sizeof(ExactWideNode<8>) : sizeof(ExactWideNode<4>);
  // Each order-free node is made from a distinct binary inner node (the collapse picks its lanes
  // among that node's descendants).
  const BvhShape object = bvh_shape(accel.nodes);
  size_t bytes = object.inner * exact_node + object.blocks * sizeof(TriBlock) +
                 2 * object.nodes * sizeof(uint32_t);  // entry_of, lane_of
  if (accel.spec.two_level()) {
    const BvhShape top = bvh_shape(accel.top_nodes);
    bytes += top.inner * exact_node + top.nodes * sizeof(uint32_t);
  }
  return bytes;
}

void check_fast_path_budget(const Accel& accel, int exact_width, size_t max_memory) {
  const size_t budget = memory_budget(max_memory);
  const size_t built = accel.bytes_total();
  const size_t fast = fast_path_bytes_at_most(accel, exact_width);
  if (built <= budget && fast <= budget - built) return;
  throw InputError("the fast path of structure '" + accel.spec.name() + "' (its wide trees and triangle blocks) would take up to " +
                   mib_text(double(fast)) + " beside the structure's " + mib_text(double(built)) + ", together " +
                   mib_text(double(fast) + double(built)) + ", over the budget of " + mib_budget_text(double(budget)) +
                   ": use a smaller scene, --exact-width 4, or raise --max-memory");
}

}  // namespace ls
