// What the fast path's trees and triangle blocks will take, bounded from the shape of a built
// structure's binary BVHs and refused against the memory budget (common/base/memory_budget.h).
#pragma once

#include "common/structure/accel.h"

#include <cstddef>

namespace ls {

// Upper bound of the bytes of the fast path's trees and triangle blocks (FastTracer::bytes()) for a
// built structure, from the shape of its binary BVHs: the order-free tree's nodes (one per binary
// inner node at most: each is made from a distinct one), ceil(count / 4) blocks per binary leaf at
// most (a leaf of the order-free tree takes no more blocks than the binary leaves it joins), and
// one index entry per binary node for each of them.  Built after the BVH, checked before the fast path is made:
// estimate_structure_bytes() covers the BVH's build, not these.
size_t fast_path_bytes_at_most(const Accel& accel, int exact_width);

// Throws InputError when accel.bytes_total() plus fast_path_bytes_at_most() exceeds
// memory_budget(max_memory).
void check_fast_path_budget(const Accel& accel, int exact_width, size_t max_memory);

}  // namespace ls
